// Stepping after a source: a transfer whose feet glide along with the body
// (the tokenizer decoded a walk's travel but not its steps: a human walk onto
// the MANN dog came out with stiff legs and feet sliding at the body's speed)
// puts its feet down in the source's rhythm.
//
//   Clip output = ...decoded onto a dog...;                      // +Y up, as preprocessing leaves it
//   StepReport r = step_after(source, output.skeleton, output.motion);
//   r.feet;                                                      // 4: the dog's feet now step
//
// The source's rhythm: its feet's touchdowns by the transfer check's contact
// rule (fitting/transfer_check.h). Feet with at least two touchdowns step; one
// of them (the back-most on the left) is the reference, and a stride is the time
// between two of its touchdowns, so the target follows the source's cadence
// where it changes. The duty factor (the share of a stride a foot is down) is
// the source's median over its stepping feet. Stepping runs from a swing before
// the source's first touchdown to a plant after its last.
//
// The target's feet are the leaf joints foot locking takes (fitting/foot_lock.h:
// near the floor, with a leg to bend) that glide: over the stepping span they
// are down by the contact rule for less than half the source's duty factor. A
// target whose feet already step is left alone, and so is a target of a
// source that does not step. Each gliding foot gets a phase offset by where it
// sits on the body (in the body's facing frame, motion/kinematic_signals.h's heading):
// left feet start at 0, right feet at one half, and on each side the feet from
// back to front take equal shares of that half. A biped alternates, a
// quadruped walks left hind, left fore, right hind, right fore, six or more
// legs pass a wave from back to front; feet near the midline (tail tips) do
// not step. The source's feet get offsets by the same rule, so a target foot
// comes down when the source's foot of the same offset does.
//
// The target steps at the source's cadence unless its body would travel
// more than `stance` leg lengths (hip to foot, stretched) over one plant at
// it: a short-legged body travelling as many body sizes per second as a
// person walks must step faster (a person walking travels about one leg
// length over a plant). Then the phase runs faster by that factor, from the
// same first touchdown.
//
// Foot k is down while frac(phase - offset_k) < duty. Each plant is pinned
// at its foot's own ground, where the decoded foot is at the plant's middle
// frame (a gliding foot keeps its place under the body, so the body passes
// over the pin); between plants the foot travels to the next pin on a smooth
// path lifted by lift_ratio of its hip's height above the ground. Before the
// first plant and after the last, the pin's shift fades over blend_frames as
// foot locking's does. The leg reaches every target with foot locking's
// two-bone IK: only the knee's and the hip's local rotations change; the
// root, and so the body's path, and every other joint keep their values.
#pragma once

#include "nec/motion/motion.h"

namespace nec {

struct StepOptions {
  double glide_ratio = 0.5;  // a target foot glides when down for less than this times the source's duty factor
  double lift_ratio = 0.2;   // swing height, times the hip's height above its ground
  double min_lift = 0.05;    // body sizes; the swing height is at least this, at most half the hip's height
  double midline = 0.1;      // a foot within this share of the widest foot's sideways distance does not step
  double stance = 1.0;       // leg lengths (hip to foot, stretched) the body may travel over one plant
  int blend_frames = 4;      // frames over which the first and last pins' shifts fade

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct StepReport {
  int feet = 0;              // target feet that now step
  int plants = 0;            // plants they make, all feet together
  double source_strides_per_second = 0.0;  // the source's cadence: strides of one foot per second (median)
  double strides_per_second = 0.0;  // the target's: the source's, or faster where its legs are too short for it
  double duty = 0.0;         // the source's duty factor
  double max_miss = 0.0;     // largest distance left between a foot and its target, body sizes (out of reach)
};

// Changes `motion` (on `skeleton`, the same frame count and rate as `source`) in place. Throws
// std::invalid_argument if the motion does not fit the skeleton, the two clips differ in frame count or
// rate, or the options are bad.
StepReport step_after(const Clip& source, const Skeleton& skeleton, Motion& motion, const StepOptions& options = {});

}  // namespace nec

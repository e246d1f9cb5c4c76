// Internal to motion synthesis: gait timing per body plan, the highest
// cadence, and the spec as it will be made (within what the legs can do).
#pragma once

#include "motion_rig.h"

namespace nec::zoo::detail {

// Gait timing per plan: speed in leg lengths per second and stride frequency
// (Hz) at that speed, and step height in leg lengths.
struct GaitTuning {
  double leg_speed = 1.5;   // typical speed, leg lengths per second
  double frequency = 1.0;   // stride cycles per second at the typical speed
  double step_height = 0.12;
};

GaitTuning gait_tuning(BodyPlan plan, Action action);
// Stride frequency at which each swing takes the shortest time allowed.
double max_gait_frequency(double duty_factor);
// The spec as it will be made: speed and turn rate clamped to the creature's
// limits, unused fields zeroed, the attack side chosen.
MotionSpec effective_spec(const Creature& creature, const Rig& rig, const MotionSpec& requested);

}  // namespace nec::zoo::detail

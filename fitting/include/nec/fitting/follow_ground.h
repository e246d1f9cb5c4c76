// Ground following: a decoded or transferred motion stands on its floor where
// its source stood on its own. Decoding predicts the root's height, and on a
// body plan unlike the training rigs it misses: a dog's walk on a held-out
// spider sank a fifth of the spider's size into the floor, and a trained
// model's outputs hover or sink by a few percent of their size on others.
//
//   Clip output = ...decoded onto a spider...;                    // +Y up, floor at y = 0
//   GroundReport r = follow_ground(source, output.skeleton, output.motion);   // transfer: the source's floor
//   GroundReport s = settle_on_ground(output.skeleton, output.motion);        // no source (decode, generate)
//
// Where a body stands is its standing level: the lowest joint's height, at
// its lowest over a centred window of window_seconds (a walk's swing or a
// short hop does not lift it; a flight longer than the window does), in body
// sizes (Skeleton::diameter()). follow_ground gives the output the standing
// level of the source (each in its own body sizes); settle_on_ground puts it
// at the floor wherever it is below settle_height body sizes (sunk, or
// hovering by a little) and leaves a body higher up (a flight) alone. The
// shift, output standing level to the wanted one, is smoothed twice over the
// same window and added to the root's height frame by frame: the body's own
// bounce within a step stays, only the slow offset goes. Nothing but the
// root's height changes.
#pragma once

#include "nec/motion/motion.h"

namespace nec {

struct GroundOptions {
  double window_seconds = 1.0;  // standing-level window and smoothing width, > 0
  double settle_height = 0.1;   // body sizes: settle_on_ground moves standing levels below this to the floor, >= 0

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct GroundReport {
  double mean_shift = 0.0;  // mean |vertical shift| over frames, body sizes (+ lifts, - lowers)
  double max_shift = 0.0;   // largest |shift|, body sizes
};

// Lifts or lowers `motion` (on `skeleton`) in place so that it stands where `source` does, window by window.
// Throws std::invalid_argument if the motion does not fit the skeleton, the two differ in frame count or
// frame rate, or the options are bad.
GroundReport follow_ground(const Clip& source, const Skeleton& skeleton, Motion& motion,
                           const GroundOptions& options = {});

// Brings `motion` down or up onto the floor (y = 0) where it stands within settle_height of it.
GroundReport settle_on_ground(const Skeleton& skeleton, Motion& motion, const GroundOptions& options = {});

}  // namespace nec

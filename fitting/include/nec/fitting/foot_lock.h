// Foot locking: feet that a motion puts down but lets slide are pinned where
// they stand, and each leg is bent to reach the pin (two-bone IK).
//
//   Clip clip = ...;                                   // +Y up, as preprocessing leaves it
//   FootLockReport r = lock_feet(clip.skeleton, clip.motion);
//   r.planted_spans;                                   // foot plants pinned
//
// A foot is a leaf joint whose own ground (the 10th percentile of its height)
// is within foot_height of the floor (the median over frames of the lowest
// joint); it is planted while it is within contact_height of its ground (body
// sizes, Skeleton::diameter()) and moves slower than contact_speed body sizes
// per second or contact_speed_ratio times the root's mean speed, whichever is
// faster: a walk whose legs do not keep up with its body (decoded motion
// often) slides its feet at a fraction of the body's speed.
//
// Over a plant the foot is pinned at its median ground position and at its
// lowest height (a pin at the median height lifted the feet of a standing dog
// off the floor); on either side the shift that the pin made at that end of
// the plant fades out over blend_frames frames. Its leg is the chain of joints
// above it up to the first joint of the limb (the child of a joint with
// several children), at most four joints, never the root: the knee (middle
// joint of the chain) bends to set the hip-to-foot distance, the hip (top
// joint) swings the foot onto the pin. Rotations below the knee, the root and
// every other joint keep their values, so bone lengths never change.
#pragma once

#include "nec/motion/motion.h"

namespace nec {

struct FootLockOptions {
  double foot_height = 0.1;           // body sizes: a foot's ground is at most this above the floor
  double contact_height = 0.04;       // body sizes above the foot's ground
  double contact_speed = 0.3;         // body sizes per second, horizontal
  double contact_speed_ratio = 0.75;  // times the root's mean horizontal speed
  int min_plant_frames = 3;           // shorter plants are left alone
  int blend_frames = 4;               // frames over which a pin's shift fades out

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct FootLockReport {
  int feet = 0;             // leaf joints pinned: near the floor, with plants and a leg to bend
  int planted_spans = 0;    // plants pinned, all feet together
  double mean_slide = 0.0;  // mean horizontal foot speed over planted frames before locking, body sizes/s
  double max_miss = 0.0;    // largest distance left between a foot and its pin, body sizes (out of reach)
};

// Changes `motion` in place; throws std::invalid_argument if it does not fit
// the skeleton or the options are bad. A motion without feet is left as is.
FootLockReport lock_feet(const Skeleton& skeleton, Motion& motion, const FootLockOptions& options = {});

}  // namespace nec

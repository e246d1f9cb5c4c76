// Heading following: a motion moved onto another skeleton (`nec transfer`) is
// steered to face where its source faced, over time. Decoded tokens integrate a
// yaw rate whose small errors add up (a straight walk comes back turned by tens
// of degrees) and start from one frame's facing, which a swaying body does not
// hold; the source's facing is known while transferring, so the drift is taken
// out.
//
//   const Clip source = prepare_for_model("human_walk.bvh", ...).clip;  // +Y up, both at one frame rate
//   Clip output = ...decoded onto a dog...;
//   HeadingReport r = follow_heading(source, output.skeleton, output.motion);
//   r.max_turn;   // degrees the output was turned at most
//
// Facing is measured as `nec eval transfer` measures it (measure_kinematics:
// left/right joints, else the head, else the root's +Z). The difference
// source - output per frame is smoothed twice with a centred moving average
// of smoothing_seconds (a least-squares line through the window near the ends,
// where it is cut short, so that a drift is followed to the last frame): the
// step-by-step sway of either body stays its own, only the slow part goes.
// The root orientation is turned by it about +Y, frame by frame.
//
// The path is turned on its own, by the smoothed angle from the output's root
// step to the source's (each step weighted by the product of the two steps'
// lengths, in body sizes): decoded motion may drift in facing while keeping
// its path (a human walk) or drift in both together (a dog, a dragon), and a
// turn of the body alone would leave the second walking off, a turn of both
// the first. Where either stands still (slower than still_speed) the path
// turns with the body. Each frame's root step is turned, so the path bends
// around the first frame's root position. Joint rotations below the root and
// bone lengths do not change.
#pragma once

#include "nec/motion/motion.h"

namespace nec {

struct HeadingOptions {
  double smoothing_seconds = 1.0;  // width of each of the two smoothing windows, > 0
  double still_speed = 0.03;       // body sizes per second under which a root step says little of the path, > 0

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

struct HeadingReport {
  double mean_turn = 0.0;       // mean |turn| of the body over frames, degrees
  double max_turn = 0.0;        // largest |turn| of the body, degrees
  double max_path_turn = 0.0;   // largest |turn| of the path, degrees
};

// Turns `motion` (on `skeleton`) in place to follow the facing of `source` frame
// by frame. Throws std::invalid_argument if the motion does not fit the
// skeleton, the two differ in frame count or frame rate, or the options are bad.
HeadingReport follow_heading(const Clip& source, const Skeleton& skeleton, Motion& motion,
                             const HeadingOptions& options = {});

}  // namespace nec

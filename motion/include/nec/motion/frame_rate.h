// Does a file's frame rate fit its motion? A BVH file's Frame Time is taken
// at its word; a wrong one (1 s per frame on continuous capture) silently
// slows or speeds the motion up. The motion's own frame-to-frame change tells:
// real motion turns its joints by 6 to 400 degrees per second on average, and
// a root that travels does so at a tenth of a body size per second or more.
//
//   FrameRateCheck check = check_frame_rate(clip);
//   if (!check.warning.empty()) std::cerr << check.warning;
#pragma once

#include "nec/motion/motion.h"

#include <string>

namespace nec {

struct FrameRateCheck {
  double turn_per_frame = 0.0;    // degrees: the median over frames of the joints' mean turn to the next frame
  double turn_per_second = 0.0;   // the same at the file's rate
  double travel_per_frame = 0.0;  // body sizes (Skeleton::diameter()): the median over frames of the root's move
  double travel_per_second = 0.0; // the same at the file's rate
  double likely_fps = 0.0;        // the rate at which the motion would move at a typical speed (0: too still to say)
  std::string warning;            // non-empty when the motion at the file's rate is implausibly slow or fast
};

// Judges the joints' turning and the root's travel: a file is flagged as too slow when either is clearly
// moving from frame to frame yet implausibly slow per second, and the other does not contradict it (a root
// that travels slowly beside joints that turn at a real pace is a slow shuffle, not a wrong rate).
FrameRateCheck check_frame_rate(const Clip& clip);

}  // namespace nec

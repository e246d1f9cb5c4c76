// Does a file's frame rate fit its motion? A BVH file's Frame Time is taken
// at its word; a wrong one (1 s per frame on continuous capture) silently
// slows or speeds the motion up. The joints' own frame-to-frame turning tells:
// real motion turns its joints by 6 to 400 degrees per second on average.
//
//   FrameRateCheck check = check_frame_rate(clip.motion);
//   if (!check.warning.empty()) std::cerr << check.warning;
#pragma once

#include "nec/motion/motion.h"

#include <string>

namespace nec {

struct FrameRateCheck {
  double turn_per_frame = 0.0;   // degrees: the median over frames of the joints' mean turn to the next frame
  double turn_per_second = 0.0;  // the same at the file's rate
  double likely_fps = 0.0;       // the rate at which the motion would turn at a typical speed (0: too still to say)
  std::string warning;           // non-empty when the turning at the file's rate is implausibly slow or fast
};

FrameRateCheck check_frame_rate(const Motion& motion);

}  // namespace nec

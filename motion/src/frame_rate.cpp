// Frame-rate plausibility from the joints' turning speed.
#include "nec/motion/frame_rate.h"

#include "nec/motion/statistics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace nec {
namespace {

// Mean joint turning speed (median over frames) of real motion, degrees per second: Bandai 6-173 (median 36),
// the MANN dog 8-399 (64), CMU 57-109 (docs/assets.md). Outside [kSlowest, kFastest] the file's rate is suspect.
constexpr double kTypicalTurnPerSecond = 40.0;
constexpr double kSlowestTurnPerSecond = 3.0;
constexpr double kFastestTurnPerSecond = 1000.0;
// A clip whose joints turn less than this per frame may just be still (an idle pose): too still to judge slowness.
constexpr double kStillTurnPerFrame = 0.1;

}  // namespace

FrameRateCheck check_frame_rate(const Motion& motion) {
  FrameRateCheck out;
  if (motion.frame_count < 10 || motion.joint_count == 0) return out;
  // Every reader of BVH pays for this: the median over at most kPairs evenly spread frame pairs is enough.
  constexpr int kPairs = 1000;
  const int step = std::max(1, (motion.frame_count - 1) / kPairs);
  std::vector<double> turns;
  for (int t = 0; t + 1 < motion.frame_count; t += step) {
    double sum = 0.0;
    for (int j = 0; j < motion.joint_count; ++j) {
      const double dot = std::min(1.0, std::abs(motion.rotation(t, j).dot(motion.rotation(t + 1, j))));
      sum += 2.0 * std::acos(dot) * 180.0 / M_PI;
    }
    turns.push_back(sum / motion.joint_count);
  }
  out.turn_per_frame = median(turns);
  out.turn_per_second = out.turn_per_frame * motion.fps;
  if (out.turn_per_frame < kStillTurnPerFrame) return out;
  out.likely_fps = kTypicalTurnPerSecond / out.turn_per_frame;
  const bool too_slow = out.turn_per_second < kSlowestTurnPerSecond && out.turn_per_frame >= kStillTurnPerFrame;
  if (too_slow || out.turn_per_second > kFastestTurnPerSecond) {
    out.warning = fmt::format(
        "the file says {:.4g} frames per second, but then its joints turn {:.3g}°/s ({:.3g}° per frame; real "
        "motion: {:.0f}-{:.0f}°/s): its rate is more likely about {:.3g} fps (give the true rate with --source-fps)",
        motion.fps, out.turn_per_second, out.turn_per_frame, kSlowestTurnPerSecond, kFastestTurnPerSecond,
        out.likely_fps);
  }
  return out;
}

}  // namespace nec

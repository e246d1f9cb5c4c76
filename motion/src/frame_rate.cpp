// Frame-rate plausibility from the joints' turning speed and the root's travel.
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
// Root travel in body sizes (the longest root-to-leaf chain) per second: a human walk is about 1.5, the
// kinematic segmenter calls 0.2 standing; a root that moves at all (kStill per frame: 0.12 body sizes/s at
// 24 fps) but under kSlowest is not real capture.
constexpr double kTypicalTravelPerSecond = 0.8;
constexpr double kSlowestTravelPerSecond = 0.1;
// Root sway of a standing capture stays under this per frame at real rates: too still to judge slowness.
constexpr double kStillTravelPerFrame = 0.005;
// Joints that turn this fast per second or more are surely real-time motion, whatever the root says (a slow
// shuffle); between kSlowest and this, a root whose travel is implausibly slow decides.
constexpr double kSurelyRealTurnPerSecond = 10.0;
// Where both witnesses move and each says the true rate is this many times the file's or more, the file is
// wrong even if neither alone is implausible (a run at 1 fps: 6°/s and 0.1 body sizes/s).
constexpr double kAgreedRateFactor = 6.0;

// Evenly spread frame pairs (t, t + 1): every reader of BVH pays for this check, and the median over at most
// 1000 pairs is enough.
std::vector<int> sampled_frames(int frame_count) {
  constexpr int kPairs = 1000;
  const int step = std::max(1, (frame_count - 1) / kPairs);
  std::vector<int> frames;
  for (int t = 0; t + 1 < frame_count; t += step) frames.push_back(t);
  return frames;
}

double median_turn_per_frame(const Motion& motion, const std::vector<int>& frames) {
  std::vector<double> turns;
  for (int t : frames) {
    double sum = 0.0;
    for (int j = 0; j < motion.joint_count; ++j) {
      const double dot = std::min(1.0, std::abs(motion.rotation(t, j).dot(motion.rotation(t + 1, j))));
      sum += 2.0 * std::acos(dot) * 180.0 / M_PI;
    }
    turns.push_back(sum / motion.joint_count);
  }
  return median(turns);
}

// The root's travel; where the root stays put and a child carries the body (Bandai's joint_Root above the
// hips, every joint with position channels), the child's.
double median_travel_per_frame(const Clip& clip, const std::vector<int>& frames) {
  const double size = clip.skeleton.diameter();
  if (!(size > 0.0)) return 0.0;
  double most = 0.0;
  for (int j = 0; j < clip.skeleton.joint_count(); ++j) {
    if (j != 0 && clip.skeleton.parents[j] != 0) continue;
    std::vector<double> travel;
    for (int t : frames) travel.push_back((clip.motion.translation(t + 1, j) - clip.motion.translation(t, j)).norm());
    most = std::max(most, median(travel));
  }
  return most / size;
}

}  // namespace

FrameRateCheck check_frame_rate(const Clip& clip) {
  const Motion& motion = clip.motion;
  FrameRateCheck out;
  if (motion.frame_count < 10 || motion.joint_count == 0) return out;
  const std::vector<int> frames = sampled_frames(motion.frame_count);
  out.turn_per_frame = median_turn_per_frame(motion, frames);
  out.turn_per_second = out.turn_per_frame * motion.fps;
  out.travel_per_frame = median_travel_per_frame(clip, frames);
  out.travel_per_second = out.travel_per_frame * motion.fps;

  const bool joints_move = out.turn_per_frame >= kStillTurnPerFrame;
  const bool root_moves = out.travel_per_frame >= kStillTravelPerFrame;
  if (!joints_move && !root_moves) return out;
  // The root's travel is the surer witness where it moves (joints of a walk turn little per frame at 120 fps).
  out.likely_fps = root_moves ? kTypicalTravelPerSecond / out.travel_per_frame
                              : kTypicalTurnPerSecond / out.turn_per_frame;
  const bool joints_slow = joints_move && out.turn_per_second < kSlowestTurnPerSecond;
  const bool joints_fast = out.turn_per_second > kFastestTurnPerSecond;
  const bool joints_surely_real = out.turn_per_second >= kSurelyRealTurnPerSecond && !joints_fast;
  const bool root_slow = root_moves && out.travel_per_second < kSlowestTravelPerSecond;
  const bool root_plausible = root_moves && !root_slow;
  const bool both_say_faster = joints_move && root_moves &&
                               kTypicalTurnPerSecond / out.turn_per_second >= kAgreedRateFactor &&
                               kTypicalTravelPerSecond / out.travel_per_second >= kAgreedRateFactor;
  const bool too_slow =
      (joints_slow && !root_plausible) || (root_slow && !joints_surely_real) || both_say_faster;
  if (!too_slow && !joints_fast) return out;
  if (joints_fast) out.likely_fps = kTypicalTurnPerSecond / out.turn_per_frame;
  out.warning = fmt::format(
      "the file says {:.4g} frames per second, but then its joints turn {:.3g}°/s ({:.3g}° per frame; real motion: "
      "{:.0f}-{:.0f}°/s) and its root travels {:.3g} body sizes/s ({:.3g} per frame; travelling capture: {:.2g} or "
      "more): its rate is more likely about {:.3g} fps, a Frame Time of {:.3g} s (give the true rate with --source-fps)",
      motion.fps, out.turn_per_second, out.turn_per_frame, kSlowestTurnPerSecond, kFastestTurnPerSecond,
      out.travel_per_second, out.travel_per_frame, kSlowestTravelPerSecond, out.likely_fps, 1.0 / out.likely_fps);
  return out;
}

}  // namespace nec

// Frame-rate plausibility: a real capture keeps quiet at its own rate and is
// flagged when its Frame Time claims 1 s per frame; --source-fps replaces it.
#include "nec/motion/clip_file.h"
#include "nec/motion/files.h"
#include "nec/motion/frame_rate.h"

#include "test_support.h"

#include <filesystem>
#include <regex>

namespace nec {
namespace {

std::string cmu_walk() {
  const std::string path = testing::cmu_bvh_dir() + "/01_01.bvh";
  return std::filesystem::exists(path) ? path : "";
}

TEST(FrameRate, RealCaptureAtItsOwnRateIsPlausible) {
  if (cmu_walk().empty()) GTEST_SKIP() << "assimp-testmodels is not installed";
  const Clip clip = read_clip(cmu_walk());
  const FrameRateCheck check = check_frame_rate(clip.motion);
  EXPECT_TRUE(check.warning.empty()) << check.warning;
  EXPECT_GT(check.turn_per_second, 10.0);
  EXPECT_LT(check.turn_per_second, 400.0);
  for (const std::string& w : clip.warnings) EXPECT_EQ(w.find("frames per second"), std::string::npos) << w;
}

TEST(FrameRate, OneSecondPerFrameOnContinuousCaptureIsFlagged) {
  if (cmu_walk().empty()) GTEST_SKIP() << "assimp-testmodels is not installed";
  testing::TempDir dir;
  const std::string text = std::regex_replace(read_file(cmu_walk()), std::regex("Frame Time:[^\\n]*"), "Frame Time: 1");
  const std::string slow = dir.write("slow.bvh", text);
  const Clip clip = read_clip(slow);
  EXPECT_DOUBLE_EQ(clip.motion.fps, 1.0);
  ASSERT_FALSE(clip.warnings.empty());
  EXPECT_NE(clip.warnings.back().find("more likely about"), std::string::npos) << clip.warnings.back();
  const double likely = check_frame_rate(clip.motion).likely_fps;
  EXPECT_GT(likely, 120.0 / 4);  // the true rate is 120 fps
  EXPECT_LT(likely, 120.0 * 4);
  // The user's rate replaces the file's, without the warning.
  ClipReadOptions options;
  options.fps = 120;
  const Clip fixed = read_clip(slow, options);
  EXPECT_DOUBLE_EQ(fixed.motion.fps, 120.0);
  for (const std::string& w : fixed.warnings) EXPECT_EQ(w.find("more likely"), std::string::npos) << w;
}

TEST(FrameRate, StillClipsAreNotJudged) {
  Skeleton s;
  s.add_joint("root", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::ZXY));
  s.add_joint("tip", 0, Vec3(0, 1, 0), ChannelLayout::rotations(EulerOrder::ZXY));
  const Motion idle = Motion::rest(s, 100, 1.0);  // one frame per second, nothing moves
  const FrameRateCheck check = check_frame_rate(idle);
  EXPECT_TRUE(check.warning.empty()) << check.warning;
  EXPECT_EQ(check.likely_fps, 0.0);
}

}  // namespace
}  // namespace nec

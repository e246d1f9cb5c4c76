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
  const FrameRateCheck check = check_frame_rate(clip);
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
  const double likely = check_frame_rate(clip).likely_fps;
  EXPECT_GT(likely, 120.0 / 4);  // the true rate is 120 fps
  EXPECT_LT(likely, 120.0 * 4);
  // The user's rate replaces the file's, without the warning.
  ClipReadOptions options;
  options.fps = 120;
  const Clip fixed = read_clip(slow, options);
  EXPECT_DOUBLE_EQ(fixed.motion.fps, 120.0);
  for (const std::string& w : fixed.warnings) EXPECT_EQ(w.find("more likely"), std::string::npos) << w;
}

Clip two_joint_clip(int frames, double fps) {
  Clip clip;
  clip.skeleton.add_joint("root", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::ZXY));
  clip.skeleton.add_joint("tip", 0, Vec3(0, 1, 0), ChannelLayout::rotations(EulerOrder::ZXY));
  clip.motion = Motion::rest(clip.skeleton, frames, fps);
  return clip;
}

// A walk at 30 fps written with Frame Time 1: joints that turn 0.06° a frame (too little to judge alone), a root
// that travels 2 % of the body's size a frame.
Clip mistimed_walk(double turn_degrees_per_frame) {
  Clip clip = two_joint_clip(600, 1.0);
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    const double swing = turn_degrees_per_frame * M_PI / 180.0 * t;
    clip.motion.rotation(t, 1) = Quat(Eigen::AngleAxisd(swing, Vec3::UnitX()));
    clip.motion.translation(t, 0) = Vec3(0, 1, 0.02 * t);
  }
  return clip;
}

TEST(FrameRate, StillClipsAreNotJudged) {
  const Clip idle = two_joint_clip(100, 1.0);  // one frame per second, nothing moves
  const FrameRateCheck check = check_frame_rate(idle);
  EXPECT_TRUE(check.warning.empty()) << check.warning;
  EXPECT_EQ(check.likely_fps, 0.0);
}

TEST(FrameRate, RootTravelFlagsAWalkTooStillInItsJointsToJudge) {
  const FrameRateCheck check = check_frame_rate(mistimed_walk(0.06));
  EXPECT_NEAR(check.travel_per_frame, 0.02, 1e-9);
  EXPECT_NEAR(check.travel_per_second, 0.02, 1e-9);
  ASSERT_FALSE(check.warning.empty());
  EXPECT_NE(check.warning.find("root travels 0.02 body sizes/s"), std::string::npos) << check.warning;
  EXPECT_GT(check.likely_fps, 15.0);  // the walk was captured at 30 fps
  EXPECT_LT(check.likely_fps, 60.0);
}

TEST(FrameRate, ARunAtOneFrameASecondIsFlaggedByBothWitnessesTogether) {
  // Joints 6°/s on average and a root at 0.1 body sizes/s: each alone could be slow real motion, together they
  // say about 7 fps.
  Clip run = mistimed_walk(12.0);
  for (int t = 0; t < run.motion.frame_count; ++t) run.motion.translation(t, 0) = Vec3(0, 1, 0.1 * t);
  const FrameRateCheck check = check_frame_rate(run);
  ASSERT_FALSE(check.warning.empty());
  EXPECT_NEAR(check.likely_fps, 8.0, 0.5);
}

TEST(FrameRate, SlowTravelBesideRealJointTurningIsAShuffleNotAWrongRate) {
  // The same root travel per second, but joints that turn 20°/s on average (40° the one that moves): a real
  // slow shuffle, so nothing is said.
  EXPECT_TRUE(check_frame_rate(mistimed_walk(40.0)).warning.empty());
  // At 30 fps the walk is plausible in both.
  Clip walk = mistimed_walk(0.06);
  walk.motion.fps = 30.0;
  EXPECT_TRUE(check_frame_rate(walk).warning.empty()) << check_frame_rate(walk).warning;
}

}  // namespace
}  // namespace nec

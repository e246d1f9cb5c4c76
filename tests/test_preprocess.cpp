// Unified preprocessing: each step, the whole pipeline and its inverse.
#include "nec/motion/bvh.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace nec {
namespace {

// A small biped standing on the ground (Y up), walking along +X, left side at -Z:
// it faces +X... left = -Z... forward = left x up = (-Z) x Y = +X.
Clip walking_biped(int frames = 40, double scale = 10.0) {
  Skeleton s;
  const auto rot = ChannelLayout::rotations(EulerOrder::ZXY);
  s.add_joint("Hips", -1, Vec3(0, 1.0 * scale, 0), ChannelLayout::position_rotations(EulerOrder::ZXY));
  s.add_joint("Spine", 0, Vec3(0, 0.5 * scale, 0), rot);
  s.add_joint("Head", 1, Vec3(0, 0.3 * scale, 0), rot);
  s.add_joint("LeftUpLeg", 0, Vec3(0, -0.1 * scale, -0.2 * scale), rot);
  s.add_joint("LeftLeg", 3, Vec3(0, -0.45 * scale, 0), rot);
  s.add_joint("LeftFoot", 4, Vec3(0, -0.45 * scale, 0), rot);
  s.add_joint("RightUpLeg", 0, Vec3(0, -0.1 * scale, 0.2 * scale), rot);
  s.add_joint("RightLeg", 6, Vec3(0, -0.45 * scale, 0), rot);
  s.add_joint("RightFoot", 7, Vec3(0, -0.45 * scale, 0), rot);
  s.end_sites.push_back({2, Vec3(0, 0.1 * scale, 0)});
  Motion m = Motion::rest(s, frames, 60.0);
  for (int t = 0; t < frames; ++t) {
    m.translation(t, 0) = Vec3(3.0 + 0.05 * scale * t, 1.0 * scale, 2.0);
    const double swing = 20.0 * std::sin(t * 0.3);
    m.rotation(t, 3) = axis_rotation(2, swing);
    m.rotation(t, 6) = axis_rotation(2, -swing);
  }
  return {s, m, {}};
}

Clip rotated(const Clip& clip, const Quat& rotation) {
  Clip out = clip;
  transform_clip(out, rotation, 1.0, Vec3::Zero());
  return out;
}

TEST(Preprocess, NormalizesScaleAxesHeadingAndRate) {
  const Clip raw = walking_biped();
  const PreparedClip p = preprocess(raw, "biped.bvh");
  ASSERT_TRUE(p.report.accepted()) << p.report.rejection;
  EXPECT_NEAR(p.clip.skeleton.diameter(), 1.0, 1e-12);
  EXPECT_NEAR(p.clip.motion.fps, 30.0, 1e-12);
  EXPECT_EQ(p.clip.motion.frame_count, 20);  // 39 frames at 60 fps = 0.65 s -> 20 frames at 30 fps
  // Root above the origin at frame 0, walking towards +Z.
  const Vec3 start = p.clip.motion.translation(0, 0);
  EXPECT_NEAR(start.x(), 0.0, 1e-9);
  EXPECT_NEAR(start.z(), 0.0, 1e-9);
  EXPECT_GT(start.y(), 0.0);
  const Vec3 travel = p.clip.motion.translation(p.clip.motion.frame_count - 1, 0) - start;
  EXPECT_GT(travel.z(), 0.1);
  EXPECT_NEAR(travel.x(), 0.0, 1e-9);
  // Left joints end up on +X.
  const Pose pose = forward_kinematics(p.clip.skeleton, p.clip.motion);
  EXPECT_GT(pose.position(0, 3).x(), 0.05);
  EXPECT_EQ(p.canonical_names[3], "left upper leg");
}

TEST(Preprocess, DenormalizeRestoresTheOriginal) {
  PreprocessOptions keep_rate;
  keep_rate.target_fps = 0.0;
  const Clip raw = rotated(walking_biped(), axis_rotation(1, 70.0));
  const PreparedClip p = preprocess(raw, "biped.bvh", keep_rate);
  ASSERT_TRUE(p.report.accepted());
  const Clip back = denormalize(p.clip, p.normalization);
  const Pose a = forward_kinematics(raw.skeleton, raw.motion);
  const Pose b = forward_kinematics(back.skeleton, back.motion);
  const double diff = testing::max_position_difference(a.positions, b.positions);
  EXPECT_LT(diff, 1e-9) << "max difference " << diff;
}

TEST(Preprocess, RenormalizePutsAClipIntoAnotherClipsFrame) {
  PreprocessOptions keep_rate;
  keep_rate.target_fps = 0.0;
  // Two files in one frame: a walk, and the same walk turned by 40° about +Y and moved. Each normalizes to
  // the same clip; put back into the first one's frame, the second is the first turned and moved there.
  const Clip first = walking_biped();
  Clip second = first;
  transform_clip(second, axis_rotation(1, 40.0), 1.0, Vec3(3.0, 0.0, -2.0));
  const PreparedClip a = preprocess(first, "a.bvh", keep_rate), b = preprocess(second, "b.bvh", keep_rate);
  const Clip same = renormalize(a.clip, a.normalization, a.normalization);
  const Clip moved = renormalize(b.clip, b.normalization, a.normalization);
  const Pose in_a = forward_kinematics(a.clip.skeleton, a.clip.motion);
  EXPECT_LT(testing::max_position_difference(in_a.positions,
                                             forward_kinematics(same.skeleton, same.motion).positions), 1e-9);
  // Expected: the second file's joints normalized the way the first file was.
  const Pose raw = forward_kinematics(second.skeleton, second.motion);
  std::vector<Vec3> wanted;
  for (const Vec3& x : raw.positions) {
    wanted.push_back(a.normalization.rotation.conjugate() * (x - a.normalization.origin) / a.normalization.scale);
  }
  const double diff = testing::max_position_difference(wanted, forward_kinematics(moved.skeleton, moved.motion).positions);
  EXPECT_LT(diff, 1e-9) << "max difference " << diff;
  EXPECT_GT(testing::max_position_difference(in_a.positions, wanted), 0.1);
}

TEST(Preprocess, HeadingAndUpAxisInvariance) {
  // The same clip turned about Y, or stored Z-up, normalizes to the same motion.
  const PreparedClip reference = preprocess(walking_biped(), "a.bvh");
  const Quat y_to_z = axis_rotation(0, 90.0);  // +Y -> +Z
  for (const Clip& variant : {rotated(walking_biped(), axis_rotation(1, -125.0)), rotated(walking_biped(), y_to_z)}) {
    const PreparedClip p = preprocess(variant, "b.bvh");
    ASSERT_TRUE(p.report.accepted());
    const Pose a = forward_kinematics(reference.clip.skeleton, reference.clip.motion);
    const Pose b = forward_kinematics(p.clip.skeleton, p.clip.motion);
    EXPECT_LT(testing::max_position_difference(a.positions, b.positions), 1e-9);
  }
  EXPECT_EQ(detect_up_axis(rotated(walking_biped(), y_to_z)), UpAxis::Z);
  EXPECT_EQ(detect_up_axis(walking_biped()), UpAxis::Y);
  // A one-frame rig in its bind pose, its toes ahead of the root, as Blender exports an armature (+Z up): CMU's
  // T-pose.
  const std::string cmu = "/usr/share/assimp/models/BVH/01_01.bvh";
  if (!std::filesystem::exists(cmu)) GTEST_SKIP() << "assimp-testmodels is not installed";
  Clip tpose = read_bvh(cmu);
  tpose.motion = Motion::rest(tpose.skeleton, 1, 30.0);
  EXPECT_EQ(detect_up_axis(tpose), UpAxis::Y);
  EXPECT_EQ(detect_up_axis(rotated(tpose, y_to_z)), UpAxis::Z);
}

TEST(Preprocess, FaceForwardAtStartUndoesATurnOfTheBody) {
  const PreparedClip p = preprocess(walking_biped(), "biped.bvh");
  ASSERT_TRUE(p.report.accepted());
  const Features truth = encode_features(p.clip.skeleton, p.clip.motion);
  // Facing +Z already: nothing to do.
  Features same = truth;
  EXPECT_NEAR(face_forward_at_start(same, p.clip.skeleton), 0.0, 1e-6);
  // A decoder that put the body 100 degrees off: turned back onto the truth, path and pose.
  Features off = truth;
  turn_body(off, 100.0 * M_PI / 180.0);
  EXPECT_NEAR(face_forward_at_start(off, p.clip.skeleton), -100.0 * M_PI / 180.0, 1e-5);
  for (size_t k = 0; k < off.data.size(); ++k) EXPECT_NEAR(off.data[k], truth.data[k], 1e-5) << k;
  // Without left or right joints: towards the head (put ahead of the spine), whatever way it faces.
  Skeleton unnamed = p.clip.skeleton;
  for (int j = 0; j < unnamed.joint_count(); ++j) {
    if (unnamed.names[j] != "Head") unnamed.names[j] = "joint" + std::to_string(j);
  }
  unnamed.offsets[2] = Vec3(0.0, 0.1, 0.2);
  Features head_first = truth;
  face_forward_at_start(head_first, unnamed);  // faces +Z by its head now
  turn_body(head_first, 0.5);
  EXPECT_NEAR(face_forward_at_start(head_first, unnamed), -0.5, 1e-5);
  // With neither: nothing.
  unnamed.names[2] = "joint2";
  Features nothing = truth;
  EXPECT_EQ(face_forward_at_start(nothing, unnamed), 0.0);
  for (size_t k = 0; k < nothing.data.size(); ++k) EXPECT_EQ(nothing.data[k], truth.data[k]) << k;
  std::mt19937 rng(1);
  EXPECT_THROW(face_forward_at_start(nothing, testing::random_skeleton(rng, 4)), std::invalid_argument);
}

TEST(Preprocess, MergesDummyRootKeepingPositions) {
  Clip raw = walking_biped();
  // Wrap in a dummy root at the origin that moves and turns the whole body.
  Skeleton s;
  s.add_joint("joint_Root", -1, Vec3::Zero(), ChannelLayout::position_rotations(EulerOrder::ZXY));
  for (int j = 0; j < raw.skeleton.joint_count(); ++j) {
    s.add_joint(raw.skeleton.names[j], raw.skeleton.parents[j] + 1, raw.skeleton.offsets[j],
                ChannelLayout::position_rotations(EulerOrder::ZXY));
  }
  for (EndSite e : raw.skeleton.end_sites) s.end_sites.push_back({e.parent + 1, e.offset});
  Motion m = Motion::rest(s, raw.motion.frame_count, raw.motion.fps);
  for (int t = 0; t < m.frame_count; ++t) {
    m.rotation(t, 0) = axis_rotation(1, t * 1.5);
    m.translation(t, 0) = Vec3(0.1 * t, 0, 0);
    for (int j = 0; j < raw.skeleton.joint_count(); ++j) {
      m.rotation(t, j + 1) = raw.motion.rotation(t, j);
      m.translation(t, j + 1) = raw.motion.translation(t, j);
    }
  }
  Clip wrapped{s, m, {}};
  const Pose before = forward_kinematics(wrapped.skeleton, wrapped.motion);
  PreprocessReport report;
  merge_dummy_root(wrapped, report);
  ASSERT_EQ(wrapped.skeleton.joint_count(), raw.skeleton.joint_count());
  EXPECT_EQ(wrapped.skeleton.names[0], "Hips");
  ASSERT_EQ(report.changes.size(), 1u);
  const Pose after = forward_kinematics(wrapped.skeleton, wrapped.motion);
  double worst = 0.0;
  for (int t = 0; t < m.frame_count; ++t) {
    for (int j = 0; j < wrapped.skeleton.joint_count(); ++j) {
      worst = std::max(worst, (after.position(t, j) - before.position(t, j + 1)).norm());
    }
  }
  EXPECT_LT(worst, 1e-9);
}

TEST(Preprocess, FoldsConstantTranslationsAndRejectsMovingOnes) {
  Clip clip = walking_biped();
  clip.skeleton.channels[1] = ChannelLayout::position_rotations(EulerOrder::ZXY);
  PreprocessReport ok;
  Clip folded = clip;
  EXPECT_TRUE(fold_joint_translations(folded, PreprocessOptions{}, ok));
  EXPECT_FALSE(folded.skeleton.channels[1].has_position());
  for (int t = 0; t < 5; ++t) clip.motion.translation(t, 1) += Vec3(0, 0.5 * t, 0);  // a stretching spine
  PreprocessReport bad;
  EXPECT_FALSE(fold_joint_translations(clip, PreprocessOptions{}, bad));
  EXPECT_NE(bad.rejection.find("'Spine'"), std::string::npos) << bad.rejection;
  EXPECT_NE(bad.rejection.find("--fold-translations"), std::string::npos) << bad.rejection;
  const PreparedClip p = preprocess(clip, "stretch.bvh");
  EXPECT_FALSE(p.report.accepted());
  PreprocessOptions anyway;
  anyway.fold_any_translation = true;
  EXPECT_TRUE(preprocess(clip, "stretch.bvh", anyway).report.accepted());
}

// 3ds Max-style exports key every joint's translation, with float noise: small
// variations fold into the offset and the report names the largest.
TEST(Preprocess, FoldsJitteringTranslationsAndReportsTheLargest) {
  Clip clip = walking_biped();
  const double diameter = clip.skeleton.diameter();
  const double bone = clip.skeleton.offsets[1].norm();
  clip.skeleton.channels[1] = ChannelLayout::position_rotations(EulerOrder::ZXY);
  const double jitter = std::min(0.004 * diameter, 0.05 * bone);  // within both limits
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    clip.motion.translation(t, 1) += Vec3(t % 2 == 0 ? jitter : -jitter, 0, 0);
  }
  PreprocessReport report;
  ASSERT_TRUE(fold_joint_translations(clip, PreprocessOptions{}, report)) << report.rejection;
  ASSERT_EQ(report.changes.size(), 1u);
  EXPECT_NE(report.changes[0].find("largest variation folded"), std::string::npos) << report.changes[0];
  EXPECT_NE(report.changes[0].find("'Spine'"), std::string::npos) << report.changes[0];
  EXPECT_NEAR((clip.motion.translation(0, 1) - clip.skeleton.offsets[1]).norm(), 0.0, 1e-12);
}

// Blender's exporter keys a zero-length bone (CMU's Neck under a 1e-6 offset) with float noise as large as the
// bone itself: noise that small against the body folds, while the same ratio on a real bone still rejects.
TEST(Preprocess, FoldsFloatNoiseOnAZeroLengthBone) {
  Clip clip = walking_biped();
  const double diameter = clip.skeleton.diameter();
  clip.skeleton.offsets[2] = Vec3(0, 1e-7 * diameter, 0);
  clip.skeleton.channels[2] = ChannelLayout::position_rotations(EulerOrder::ZXY);
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    clip.motion.translation(t, 2) = clip.skeleton.offsets[2] + Vec3(t % 2 == 0 ? 5e-8 * diameter : 0, 0, 0);
  }
  PreprocessReport report;
  EXPECT_TRUE(fold_joint_translations(clip, PreprocessOptions{}, report)) << report.rejection;
  Clip stretched = walking_biped();  // a short real bone (half a percent of the body) stretching by 30 %
  stretched.skeleton.offsets[2] = Vec3(0, 0.005 * diameter, 0);
  stretched.skeleton.channels[2] = ChannelLayout::position_rotations(EulerOrder::ZXY);
  for (int t = 0; t < stretched.motion.frame_count; ++t) {
    stretched.motion.translation(t, 2) = stretched.skeleton.offsets[2] + Vec3(t % 2 == 0 ? 0.0015 * diameter : 0, 0, 0);
  }
  PreprocessReport bad;
  EXPECT_FALSE(fold_joint_translations(stretched, PreprocessOptions{}, bad));
}

TEST(Preprocess, RejectsAbnormalBonesAndEmptyClips) {
  Clip clip = walking_biped();
  clip.skeleton.offsets[2] = Vec3(0, 500.0, 0);  // a corrupted head bone
  EXPECT_NE(preprocess(clip, "long.bvh").report.rejection.find("'Head'"), std::string::npos);
  Clip one = walking_biped(1);
  EXPECT_FALSE(preprocess(one, "one.bvh").report.accepted());
}

TEST(Preprocess, ResampleKeepsEndpointsAndInterpolates) {
  const Clip clip = walking_biped(61);
  const Motion half = resample(clip.motion, 30.0);
  ASSERT_EQ(half.frame_count, 31);
  EXPECT_LT(geodesic_distance(half.rotation(10, 3), clip.motion.rotation(20, 3)), 1e-12);
  const Motion up = resample(clip.motion, 120.0);
  ASSERT_EQ(up.frame_count, 121);
  const Vec3 mid = 0.5 * (clip.motion.translation(0, 0) + clip.motion.translation(1, 0));
  EXPECT_LT((up.translation(1, 0) - mid).norm(), 1e-12);
}

TEST(Preprocess, RealFilesAreAccepted) {
  for (const auto& path : testing::bvh_files_under(testing::cmu_bvh_dir())) {
    const PreparedClip p = preprocess(read_bvh(path), path);
    EXPECT_TRUE(p.report.accepted()) << path << ": " << p.report.rejection;
    EXPECT_NEAR(p.clip.skeleton.diameter(), 1.0, 1e-9);
  }
  const std::string shared = testing::shared_data_dir();
  if (shared.empty()) return;
  const std::string bandai = shared + "/bandai/set1/data/dataset-1_walk_normal_001.bvh";
  const PreparedClip p = preprocess(read_bvh(bandai), bandai);
  ASSERT_TRUE(p.report.accepted()) << p.report.rejection;
  EXPECT_EQ(p.clip.skeleton.names[0], "Hips");  // dummy joint_Root merged
  // Walks forward: +Z after normalization.
  const Motion& m = p.clip.motion;
  EXPECT_GT(m.translation(m.frame_count - 1, 0).z(), 0.3);
}

}  // namespace
}  // namespace nec

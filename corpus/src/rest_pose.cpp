// Joint-frame conventions: re-expressing a rig, the mean-pose canonical rest, other authoring conventions, and
// the stance taken from the skeleton alone (stance.h).
#include "nec/corpus/rest_pose.h"
#include "nec/corpus/stance.h"

#include "nec/motion/kinematics.h"

#include <Eigen/SVD>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nec {
namespace {

void check_frame_count(const Skeleton& skeleton, const std::vector<Quat>& frames, const char* what) {
  if (static_cast<int>(frames.size()) != skeleton.joint_count()) {
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(frames.size()) + " joint frames for " +
                                std::to_string(skeleton.joint_count()) + " joints");
  }
}

// The rotation nearest to `sum` (a sum of rotation matrices) in the Frobenius norm.
Quat nearest_rotation(const Mat3& sum) {
  if (sum.norm() < 1e-12) return Quat::Identity();
  const Eigen::JacobiSVD<Mat3> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 fix = Mat3::Identity();
  fix(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return Quat(svd.matrixU() * fix * svd.matrixV().transpose()).normalized();
}

// A uniformly distributed unit quaternion (Shoemake), from the portable generator.
Quat random_rotation(SplitMix64& rng) {
  constexpr double kTwoPi = 6.28318530717958647692;
  const double u1 = rng.uniform(), u2 = rng.uniform(), u3 = rng.uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  return Quat(b * std::cos(kTwoPi * u3), a * std::sin(kTwoPi * u2), a * std::cos(kTwoPi * u2), b * std::sin(kTwoPi * u3))
      .normalized();
}

}  // namespace

Skeleton reexpress_skeleton(const Skeleton& skeleton, const std::vector<Quat>& frames) {
  check_frame_count(skeleton, frames, "reexpress_skeleton");
  Skeleton out = skeleton;
  for (int j = 1; j < out.joint_count(); ++j) out.offsets[j] = frames[out.parents[j]] * skeleton.offsets[j];
  for (EndSite& site : out.end_sites) site.offset = frames[site.parent] * site.offset;
  return out;
}

Clip reexpress_joint_frames(const Clip& clip, const std::vector<Quat>& frames) {
  const Skeleton& s = clip.skeleton;
  check_frame_count(s, frames, "reexpress_joint_frames");
  Clip out = clip;
  out.skeleton = reexpress_skeleton(s, frames);
  Motion& m = out.motion;
  for (int t = 0; t < m.frame_count; ++t) {
    m.rotation(t, 0) = (clip.motion.rotation(t, 0) * frames[0].conjugate()).normalized();
    for (int j = 1; j < s.joint_count(); ++j) {
      const Quat& parent = frames[s.parents[j]];
      m.rotation(t, j) = (parent * clip.motion.rotation(t, j) * frames[j].conjugate()).normalized();
      m.translation(t, j) = parent * clip.motion.translation(t, j);
    }
  }
  return out;
}

std::vector<Quat> inverse_frames(const std::vector<Quat>& frames) {
  std::vector<Quat> out;
  out.reserve(frames.size());
  for (const Quat& f : frames) out.push_back(f.conjugate());
  return out;
}

MeanPoseFrames::MeanPoseFrames(const Skeleton& skeleton)
    : skeleton_(skeleton), sums_(skeleton.joint_count(), Mat3::Zero()) {}

void MeanPoseFrames::add(const Motion& motion, const std::vector<Quat>& frames) {
  const int joints = skeleton_.joint_count();
  if (motion.joint_count != joints) {
    throw std::invalid_argument("MeanPoseFrames::add: a motion of " + std::to_string(motion.joint_count) +
                                " joints on a rig of " + std::to_string(joints));
  }
  if (!frames.empty()) check_frame_count(skeleton_, frames, "MeanPoseFrames::add");
  if (motion.frame_count == 0) return;
  const Pose pose = forward_kinematics(skeleton_, motion);
  const Quat start_inverse = pose.rotation(0, 0).conjugate();
  for (int t = 0; t < motion.frame_count; ++t) {
    // The root's turn since frame 0 is the same in every convention (G -> G D cancels in G_t G_0^-1).
    const Quat unturn = heading_rotation((pose.rotation(t, 0) * start_inverse).normalized()).conjugate();
    for (int j = 0; j < joints; ++j) {
      const Quat authored = frames.empty() ? pose.rotation(t, j) : pose.rotation(t, j) * frames[j];
      sums_[j] += (unturn * authored).normalized().toRotationMatrix();
    }
  }
}

std::vector<Quat> MeanPoseFrames::frames() const {
  std::vector<Quat> out;
  out.reserve(sums_.size());
  for (const Mat3& sum : sums_) out.push_back(nearest_rotation(sum));
  return out;
}

std::vector<Quat> mean_pose_frames(const Clip& clip) {
  MeanPoseFrames mean(clip.skeleton);
  mean.add(clip.motion);
  return mean.frames();
}

Clip reorient_joint_axes(const Clip& clip, JointAxes axes, SplitMix64& rng) {
  const Skeleton& s = clip.skeleton;
  std::vector<Quat> frames(s.joint_count(), Quat::Identity());
  if (axes == JointAxes::Random) {
    for (Quat& f : frames) f = random_rotation(rng);
    return reexpress_joint_frames(clip, frames);
  }
  // The bone each joint's +X follows: to its first child, else to its end site.
  std::vector<Vec3> bone(s.joint_count(), Vec3::Zero());
  for (const EndSite& site : s.end_sites) {
    if (bone[site.parent].isZero()) bone[site.parent] = site.offset;
  }
  for (int j = s.joint_count() - 1; j >= 1; --j) {
    if (!s.offsets[j].isZero()) bone[s.parents[j]] = s.offsets[j];  // descending: the first child wins
  }
  for (int j = 0; j < s.joint_count(); ++j) {
    if (!bone[j].isZero()) frames[j] = Quat::FromTwoVectors(bone[j], Vec3::UnitX()).normalized();
  }
  return reexpress_joint_frames(clip, frames);
}

std::vector<Quat> pose_frames(const Clip& clip, int frame) {
  if (frame < 0 || frame >= clip.motion.frame_count) {
    throw std::invalid_argument("pose_frames: frame " + std::to_string(frame) + " of a clip of " +
                                std::to_string(clip.motion.frame_count));
  }
  const Pose pose = forward_kinematics(clip.skeleton, clip.motion.slice(frame, frame + 1));
  return pose.rotations;
}

std::vector<Vec3> unit_bones(const Skeleton& skeleton) {
  std::vector<Vec3> out(skeleton.joint_count(), Vec3::Zero());
  for (int j = 1; j < skeleton.joint_count(); ++j) {
    const double length = skeleton.offsets[j].norm();
    if (length > 1e-9) out[j] = skeleton.offsets[j] / length;
  }
  return out;
}

std::vector<Vec3> BindPoseStance::bone_directions(const Skeleton& bind, const std::vector<std::string>&) const {
  return unit_bones(bind);
}

std::vector<Quat> stance_frames(const Skeleton& bind, const std::vector<Vec3>& directions) {
  const int joints = bind.joint_count();
  if (static_cast<int>(directions.size()) != joints) {
    throw std::invalid_argument("stance_frames: " + std::to_string(directions.size()) + " directions for " +
                                std::to_string(joints) + " joints");
  }
  const std::vector<Vec3> bones = unit_bones(bind);
  const std::vector<std::vector<int>> children = bind.children_lists();
  std::vector<Quat> out(joints, Quat::Identity());
  for (const int j : bind.depth_first_order()) {
    const Quat parent = j == 0 ? Quat::Identity() : out[bind.parents[j]];
    Mat3 sum = Mat3::Zero();
    Vec3 from = Vec3::Zero(), to = Vec3::Zero();
    for (const int c : children[j]) {
      const double length = directions[c].norm();
      if (bones[c].isZero() || !(length > 1e-9)) continue;
      sum += (directions[c] / length) * bones[c].transpose();
      from += bones[c];
      to += directions[c] / length;
    }
    // Children that span a plane fix the whole turn; one child (or a line of them) leaves the turn about the
    // bone free, and the parent's rotation decides it: the chain swings without twisting.
    const Eigen::JacobiSVD<Mat3> svd(sum);
    const Eigen::Vector3d spread = svd.singularValues();
    if (spread(0) < 1e-12) {
      out[j] = parent;
    } else if (spread(1) < 0.01 * spread(0)) {
      out[j] = (Quat::FromTwoVectors(parent * from, to) * parent).normalized();
    } else {
      out[j] = nearest_rotation(sum);
    }
  }
  return out;
}

namespace {

// A rig the stance (and the motion) cannot do much with: one chain, or chains of no length.
void warn_of_degenerate_bones(const Skeleton& skeleton, std::vector<std::string>& warnings) {
  const int joints = skeleton.joint_count();
  bool branches = false;
  for (int j = 0; j < joints && !branches; ++j) branches = skeleton.children(j).size() >= 2;
  if (!branches) {
    warnings.push_back(joints == 1 ? "the skeleton is a single joint: the motion can only move and turn it"
                                   : "the skeleton is one chain, no limbs: the motion can only bend it");
  }
  // A collapsed chain: a joint on its parent with nothing below it reaching out either (a dummy joint on its
  // parent, like CMU's LHipJoint, has a leg below it and is fine).
  std::vector<double> reach(joints, 0.0);  // length of the bones and end sites below each joint
  for (const EndSite& site : skeleton.end_sites) reach[site.parent] += site.offset.norm();
  for (int j = joints - 1; j > 0; --j) reach[skeleton.parents[j]] += reach[j] + skeleton.offsets[j].norm();
  const double tiny = 1e-9 * std::max(skeleton.diameter(), 1e-9);
  const auto collapsed = [&](int j) { return j > 0 && skeleton.offsets[j].norm() < tiny && reach[j] < tiny; };
  std::vector<std::string> chains;
  int lying = 0;
  for (int j = 1; j < joints; ++j) {
    if (!collapsed(j)) continue;
    ++lying;
    if (!collapsed(skeleton.parents[j])) chains.push_back(skeleton.names[j]);
  }
  if (!chains.empty()) {
    std::string listed;
    for (size_t i = 0; i < chains.size() && i < 4; ++i) listed += (i ? ", " : "") + chains[i];
    if (chains.size() > 4) listed += fmt::format(" and {} more", chains.size() - 4);
    warnings.push_back(fmt::format("{} joint(s) lie on their parents with nothing below them reaching out (the "
                                   "chains from {}): they turn with their parents, with no stance of their own",
                                   lying, listed));
  }
}

}  // namespace

PreparedClip take_stance(const PreparedClip& prepared, const StancePredictor& predictor) {
  const int joints = prepared.clip.skeleton.joint_count();
  if (static_cast<int>(prepared.normalization.rest_frames.size()) != joints) {
    throw std::invalid_argument("take_stance: the clip has no canonical rest frames (prepared with --keep-rest?)");
  }
  PreparedClip out = prepared;
  const std::vector<Quat> bind = pose_frames(prepared.clip, 0);
  out.clip = reexpress_joint_frames(prepared.clip, bind);
  const std::vector<Quat> stance =
      stance_frames(out.clip.skeleton, predictor.bone_directions(out.clip.skeleton, prepared.canonical_names));
  out.clip = reexpress_joint_frames(out.clip, stance);
  // Re-expressing with A, then B, is re-expressing with B A.
  for (int j = 0; j < joints; ++j) {
    out.normalization.rest_frames[j] = (stance[j] * bind[j] * prepared.normalization.rest_frames[j]).normalized();
  }
  out.report.changes.push_back("rest: the stance predicted from the skeleton in its frame-0 pose");
  warn_of_degenerate_bones(out.clip.skeleton, out.report.warnings);
  return out;
}

std::vector<double> bone_direction_errors(const Skeleton& predicted, const Skeleton& truth,
                                          std::vector<double>* lengths) {
  if (predicted.parents != truth.parents) {
    throw std::invalid_argument("bone_direction_errors: the skeletons are not one tree");
  }
  const std::vector<Vec3> a = unit_bones(predicted), b = unit_bones(truth);
  std::vector<double> out;
  if (lengths) lengths->clear();
  for (size_t j = 0; j < a.size(); ++j) {
    if (a[j].isZero() || b[j].isZero()) continue;
    out.push_back(std::acos(std::clamp(a[j].dot(b[j]), -1.0, 1.0)) * kDegreesPerRadian);
    if (lengths) lengths->push_back(truth.offsets[j].norm());
  }
  return out;
}

}  // namespace nec

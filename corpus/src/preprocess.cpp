// Unified preprocessing: one clean tree, root-only translation, unit diameter,
// +Y up, frame 0 facing +Z, corpus frame rate.
#include "nec/corpus/preprocess.h"

#include "nec/motion/bvh.h"
#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"
#include "nec/motion/features.h"
#include "nec/motion/kinematics.h"
#include "nec/motion/names.h"
#include "nec/corpus/rest_pose.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nec {
namespace {

bool looks_like_dummy_name(const std::string& name) {
  for (const std::string& w : split_joint_name(name)) {
    if (w == "root" || w == "reference" || w == "world" || w == "armature" || w == "scene" || w == "origin" ||
        w == "master" || w == "trajectory") {
      return true;
    }
  }
  return false;
}

// Sampled FK positions: at most `max_frames` evenly spaced frames.
std::vector<Vec3> sampled_positions(const Clip& clip, int max_frames, int& frames_out) {
  const Motion& m = clip.motion;
  const int stride = std::max(1, m.frame_count / std::max(1, max_frames));
  Motion sampled = Motion::rest(clip.skeleton, 0, m.fps);
  sampled.frame_count = 0;
  for (int t = 0; t < m.frame_count; t += stride) {
    for (int j = 0; j < m.joint_count; ++j) {
      sampled.rotations.push_back(m.rotation(t, j));
      sampled.translations.push_back(m.translation(t, j));
    }
    ++sampled.frame_count;
  }
  std::vector<Vec3> positions;
  joint_positions(clip.skeleton, sampled, positions);
  frames_out = sampled.frame_count;
  return positions;
}

// Horizontal forward direction of a pose (+Y up) from its left and right joints: left x up.
bool forward_from_sides(const Skeleton& s, const Pose& pose, Vec3& forward) {
  Vec3 left = Vec3::Zero(), right = Vec3::Zero();
  int left_count = 0, right_count = 0;
  for (int j = 0; j < s.joint_count(); ++j) {
    const Side side = joint_side(s.names[j]);
    if (side == Side::Left) {
      left += pose.position(0, j);
      ++left_count;
    } else if (side == Side::Right) {
      right += pose.position(0, j);
      ++right_count;
    }
  }
  if (left_count == 0 || right_count == 0) return false;
  Vec3 lateral = left / left_count - right / right_count;
  lateral.y() = 0.0;
  if (lateral.norm() <= 0.02 * std::max(s.diameter(), 1e-12)) return false;
  forward = lateral.cross(Vec3::UnitY()).normalized();
  return true;
}

// ... from the root towards the first joint named like a head.
bool forward_from_head(const Skeleton& s, const Pose& pose, Vec3& forward) {
  for (int j = 0; j < s.joint_count(); ++j) {
    if (canonical_joint_name(s.names[j]).find("head") == std::string::npos) continue;
    Vec3 to_head = pose.position(0, j) - pose.position(0, 0);
    to_head.y() = 0.0;
    if (to_head.norm() > 0.05 * std::max(s.diameter(), 1e-12)) {
      forward = to_head.normalized();
      return true;
    }
  }
  return false;
}

// Horizontal forward direction of frame 0 (after +Y is up), and how it was found.
bool frame0_forward(const Clip& clip, Vec3& forward, std::string& how) {
  const Motion& m = clip.motion;
  const Pose pose = forward_kinematics(clip.skeleton, m.slice(0, 1));
  if (forward_from_sides(clip.skeleton, pose, forward)) {
    how = "from its left and right joints";
    return true;
  }
  Vec3 travel = m.translation(m.frame_count - 1, 0) - m.translation(0, 0);
  travel.y() = 0.0;
  if (travel.norm() > 0.1 * std::max(clip.skeleton.diameter(), 1e-12)) {
    forward = travel.normalized();
    how = "from its direction of travel";
    return true;
  }
  if (forward_from_head(clip.skeleton, pose, forward)) {
    how = "from the direction of its head";
    return true;
  }
  return false;
}

}  // namespace

void merge_dummy_root(Clip& clip, PreprocessReport& report) {
  Skeleton& s = clip.skeleton;
  const auto root_children = s.children(0);
  if (root_children.size() != 1 || s.joint_count() < 2) return;
  for (const EndSite& site : s.end_sites) {
    if (site.parent == 0) return;
  }
  const int child = root_children[0];
  const double diameter = std::max(s.diameter(), 1e-12);
  const bool far_from_body = s.offsets[child].norm() > 0.25 * diameter;
  if (!looks_like_dummy_name(s.names[0]) && !far_from_body) return;

  Motion& m = clip.motion;
  Skeleton merged;
  ChannelLayout layout = s.channels[child];
  if (!layout.has_position()) layout = ChannelLayout::position_rotations(layout.euler_order());
  merged.add_joint(s.names[child], -1, s.offsets[0] + s.offsets[child], layout);
  // Old joint j >= 2 becomes j - 1; the child (1) becomes 0.
  for (int j = 2; j < s.joint_count(); ++j) {
    merged.add_joint(s.names[j], s.parents[j] - 1, s.offsets[j], s.channels[j]);
  }
  for (EndSite site : s.end_sites) {
    site.parent -= 1;
    merged.end_sites.push_back(site);
  }
  Motion out = Motion::rest(merged, m.frame_count, m.fps);
  for (int t = 0; t < m.frame_count; ++t) {
    out.rotation(t, 0) = (m.rotation(t, 0) * m.rotation(t, child)).normalized();
    out.translation(t, 0) = m.translation(t, 0) + m.rotation(t, 0) * m.translation(t, child);
    for (int j = 2; j < s.joint_count(); ++j) {
      out.rotation(t, j - 1) = m.rotation(t, j);
      out.translation(t, j - 1) = m.translation(t, j);
    }
  }
  report.changes.push_back(fmt::format("merged dummy root '{}' into '{}'", s.names[0], s.names[child]));
  clip.skeleton = std::move(merged);
  clip.motion = std::move(out);
}

bool fold_joint_translations(Clip& clip, const PreprocessOptions& options, PreprocessReport& report) {
  Skeleton& s = clip.skeleton;
  Motion& m = clip.motion;
  int folded = 0;
  // Means first, so the diameter reflects the bones the clip actually has.
  std::vector<Vec3> means(s.joint_count(), Vec3::Zero());
  for (int j = 1; j < s.joint_count(); ++j) {
    if (!s.channels[j].has_position() || m.frame_count == 0) continue;
    for (int t = 0; t < m.frame_count; ++t) means[j] += m.translation(t, j);
    means[j] /= m.frame_count;
    s.offsets[j] = means[j];
  }
  const double diameter = std::max(s.diameter(), 1e-12);
  double largest = 0.0;  // the largest variation folded, and where
  int largest_joint = -1;
  for (int j = 1; j < s.joint_count(); ++j) {
    if (!s.channels[j].has_position()) continue;
    double deviation = 0.0;
    for (int t = 0; t < m.frame_count; ++t) deviation = std::max(deviation, (m.translation(t, j) - means[j]).norm());
    const double bone = means[j].norm();
    const bool stretches = deviation > options.translation_tolerance * diameter ||
                           (deviation > options.translation_bone_tolerance * bone &&
                            deviation > options.translation_noise * diameter);
    if (stretches && !options.fold_any_translation) {
      report.rejection = fmt::format(
          "joint '{}' moves relative to its parent by up to {:.3g} ({:.3g} diameters, {:.3g} of its bone; limits "
          "{:.3g} and {:.3g}): translation is allowed only at the root (fold it anyway with --fold-translations)",
          s.names[j], deviation, deviation / diameter, bone > 0.0 ? deviation / bone : INFINITY,
          options.translation_tolerance, options.translation_bone_tolerance);
      return false;
    }
    if (deviation > largest && deviation > 1e-9 * diameter) {  // below: float noise, a constant channel
      largest = deviation;
      largest_joint = j;
    }
    for (int t = 0; t < m.frame_count; ++t) m.translation(t, j) = means[j];
    ChannelLayout rotations_only;
    for (int c = 0; c < s.channels[j].count; ++c) {
      if (!is_position(s.channels[j].channels[c])) rotations_only.push(s.channels[j].channels[c]);
    }
    s.channels[j] = rotations_only;
    ++folded;
  }
  if (folded > 0 && largest_joint < 0) {
    report.changes.push_back(fmt::format("folded constant position channels of {} joint(s) into offsets", folded));
  } else if (folded > 0) {
    report.changes.push_back(fmt::format(
        "folded position channels of {} joint(s) into offsets (their mean); the largest variation folded: {:.3g} "
        "({:.3g} diameters, {:.3g} of the bone) at '{}'",
        folded, largest, largest / diameter, largest / std::max(means[largest_joint].norm(), 1e-12),
        s.names[largest_joint]));
  }
  return true;
}

UpAxis detect_up_axis(const Clip& clip) {
  int frames = 0;
  const std::vector<Vec3> positions = sampled_positions(clip, 200, frames);
  const Skeleton& s = clip.skeleton;
  const int joints = s.joint_count();
  const double diameter = std::max(s.diameter(), 1e-12);
  auto position = [&](int t, int j) -> const Vec3& { return positions[static_cast<size_t>(t) * joints + j]; };

  // Feet hang below the root along the up axis.
  std::vector<int> feet;
  for (int j = 1; j < joints; ++j) {
    const std::string name = canonical_joint_name(s.names[j]);
    if (name.find("foot") != std::string::npos || name.find("toe") != std::string::npos) feet.push_back(j);
  }
  if (!feet.empty()) {
    // Along the up axis the feet are below the root in nearly every frame;
    // along a horizontal axis they lie on both sides (left and right, front
    // and back) or level with it. `side` is (below - above) / pairs. Y stays
    // unless Z is clearly the up axis and Y clearly is not.
    const double margin = 0.02 * diameter;
    double side_y = 0.0, side_z = 0.0, depth_y = 0.0, depth_z = 0.0;
    for (int t = 0; t < frames; ++t) {
      for (int f : feet) {
        const Vec3 down = position(t, 0) - position(t, f);
        side_y += (down.y() > margin) - (down.y() < -margin);
        side_z += (down.z() > margin) - (down.z() < -margin);
        depth_y += down.y();
        depth_z += down.z();
      }
    }
    const double pairs = static_cast<double>(frames) * feet.size();
    side_y /= pairs;
    side_z /= pairs;
    if (side_z > 0.8 && side_y < 0.3) return UpAxis::Z;
    // A rig given as one frame (its bind pose) can have every toe ahead of the root too: then the axis the feet
    // hang far along is the up axis (a T-pose's legs: half its size down, its toes a tenth forward). Only there:
    // in motion, a lying or sitting body can hang its feet along a horizontal axis.
    if (clip.motion.frame_count == 1 && side_z > 0.8 && depth_z > 3.0 * std::abs(depth_y)) return UpAxis::Z;
    if (side_y > 0.5) return UpAxis::Y;
  }
  // Without named feet there is no reliable cue (jumps and flight move the
  // lowest joint as much as travel does): keep the BVH convention, +Y up.
  return UpAxis::Y;
}

Motion resample(const Motion& motion, double fps) {
  if (motion.frame_count < 2 || std::abs(motion.fps - fps) < 1e-9) {
    Motion same = motion;
    same.fps = fps > 0 ? fps : motion.fps;
    return same;
  }
  const double duration = (motion.frame_count - 1) / motion.fps;
  const int frames = static_cast<int>(std::floor(duration * fps + 1e-9)) + 1;
  Motion out;
  out.fps = fps;
  out.frame_count = frames;
  out.joint_count = motion.joint_count;
  out.rotations.resize(static_cast<size_t>(frames) * out.joint_count);
  out.translations.resize(out.rotations.size());
  for (int i = 0; i < frames; ++i) {
    const double source = i / fps * motion.fps;
    const int i0 = std::min(static_cast<int>(std::floor(source)), motion.frame_count - 1);
    const int i1 = std::min(i0 + 1, motion.frame_count - 1);
    const double alpha = source - i0;
    for (int j = 0; j < out.joint_count; ++j) {
      out.rotation(i, j) = motion.rotation(i0, j).slerp(alpha, motion.rotation(i1, j)).normalized();
      out.translation(i, j) = (1.0 - alpha) * motion.translation(i0, j) + alpha * motion.translation(i1, j);
    }
  }
  return out;
}

void transform_clip(Clip& clip, const Quat& rotation, double scale, const Vec3& origin) {
  Skeleton& s = clip.skeleton;
  Motion& m = clip.motion;
  s.offsets[0] = rotation * (scale * s.offsets[0]) + origin;
  for (int j = 1; j < s.joint_count(); ++j) s.offsets[j] *= scale;
  for (EndSite& site : s.end_sites) site.offset *= scale;
  for (int t = 0; t < m.frame_count; ++t) {
    m.rotation(t, 0) = (rotation * m.rotation(t, 0)).normalized();
    m.translation(t, 0) = rotation * (scale * m.translation(t, 0)) + origin;
    for (int j = 1; j < m.joint_count; ++j) m.translation(t, j) *= scale;
  }
}

Clip denormalize(const Clip& normalized, const Normalization& normalization) {
  // The rigid transform acts on the left of the root's rotation, the joint frames on the right: either order.
  Clip out = normalization.rest_frames.empty()
                 ? normalized
                 : reexpress_joint_frames(normalized, inverse_frames(normalization.rest_frames));
  transform_clip(out, normalization.rotation, normalization.scale, normalization.origin);
  return out;
}

Clip renormalize(const Clip& normalized, const Normalization& from, const Normalization& to) {
  Clip out = normalized;
  transform_clip(out, from.rotation, from.scale, from.origin);
  const Quat back = to.rotation.conjugate();
  transform_clip(out, back, 1.0 / to.scale, -(back * to.origin) / to.scale);
  return out;
}

PreparedClip preprocess(const Clip& raw, const std::string& file, const PreprocessOptions& options) {
  PreparedClip out;
  out.clip = raw;
  out.clip.warnings.clear();
  PreprocessReport& report = out.report;
  report.file = file;
  for (const std::string& warning : raw.warnings) report.changes.push_back("reader: " + warning);
  Clip& clip = out.clip;
  out.normalization.source_fps = raw.motion.fps;

  if (clip.motion.frame_count < options.min_frames) {
    report.rejection = fmt::format("only {} frame(s); at least {} needed", clip.motion.frame_count, options.min_frames);
    return out;
  }
  // 1-2. One tree with translation only at the root.
  merge_dummy_root(clip, report);
  if (!fold_joint_translations(clip, options, report)) return out;

  // 3. Abnormal bones.
  const double diameter = clip.skeleton.diameter();
  if (!(diameter > 1e-9)) {
    report.rejection = "the skeleton has zero size (all offsets are zero)";
    return out;
  }
  const std::vector<double> lengths = clip.skeleton.bone_lengths();
  for (int j = 1; j < clip.skeleton.joint_count(); ++j) {
    if (lengths[j] > options.max_bone_ratio * diameter) {
      report.rejection = fmt::format("bone to '{}' is {:.3g} diameters long (limit {:.3g})", clip.skeleton.names[j],
                                     lengths[j] / diameter, options.max_bone_ratio);
      return out;
    }
  }

  // 4. Canonical names.
  for (const std::string& name : clip.skeleton.names) out.canonical_names.push_back(canonical_joint_name(name));

  // 5-6. Scale, up axis, heading and ground origin.
  UpAxis up = options.up;
  if (up == UpAxis::Auto) up = detect_up_axis(clip);
  const Quat up_fix = up == UpAxis::Z ? axis_rotation(0, -90.0) : Quat::Identity();  // +Z -> +Y
  transform_clip(clip, up_fix, 1.0 / diameter, Vec3::Zero());
  report.changes.push_back(fmt::format("scaled by 1/{:.6g} (the skeleton diameter)", diameter));
  if (up == UpAxis::Z) report.changes.push_back("rotated the up axis from +Z to +Y");

  Vec3 forward;
  std::string how;
  Quat heading_fix = Quat::Identity();
  if (frame0_forward(clip, forward, how)) {
    const double yaw = std::atan2(forward.x(), forward.z());  // angle from +Z towards +X
    heading_fix = axis_rotation(1, -yaw * kDegreesPerRadian);
    report.changes.push_back(fmt::format("turned by {:.1f} degrees so frame 0 faces +Z ({})", -yaw * kDegreesPerRadian, how));
  } else {
    report.changes.push_back("kept the heading: no left/right joints, travel or head to find where it faces");
  }
  transform_clip(clip, heading_fix, 1.0, Vec3::Zero());
  const Vec3 start = clip.motion.translation(0, 0);
  const Vec3 shift(-start.x(), 0.0, -start.z());
  transform_clip(clip, Quat::Identity(), 1.0, shift);

  // The root's rest offset only matters when it has no position channels:
  // give it position channels and a zero offset, so clips of one rig share
  // one normalized skeleton.
  if (!clip.skeleton.channels[0].has_position()) {
    clip.skeleton.channels[0] = ChannelLayout::position_rotations(clip.skeleton.channels[0].euler_order());
  }
  clip.skeleton.offsets[0] = Vec3::Zero();

  // original = R * (diameter * normalized) + origin, with R = up_fix^-1 * heading_fix^-1.
  const Quat to_original = (up_fix.conjugate() * heading_fix.conjugate()).normalized();
  out.normalization.scale = diameter;
  out.normalization.rotation = to_original;
  out.normalization.origin = -(to_original * (diameter * shift));

  // 7. Corpus frame rate.
  // Rates within 0.01% are the same rate written with rounding (1/0.0333333).
  if (options.target_fps > 0 && std::abs(clip.motion.fps - options.target_fps) > 1e-4 * options.target_fps) {
    const int before = clip.motion.frame_count;
    const double source_fps = clip.motion.fps;
    clip.motion = resample(clip.motion, options.target_fps);
    report.changes.push_back(fmt::format("resampled {:.4g} -> {:.4g} fps ({} -> {} frames)", source_fps,
                                         options.target_fps, before, clip.motion.frame_count));
  } else if (options.target_fps > 0) {
    clip.motion.fps = options.target_fps;
    if (clip.motion.frame_count < options.min_frames) {
      report.rejection = fmt::format("only {} frame(s) after resampling", clip.motion.frame_count);
      return out;
    }
  }

  // 8. Canonical rest: the clip's mean pose, world-aligned joint frames (every position unchanged).
  if (options.canonical_rest) {
    out.normalization.rest_frames = mean_pose_frames(clip);
    clip = reexpress_joint_frames(clip, out.normalization.rest_frames);
    report.changes.push_back("re-expressed in the canonical rest pose (the clip's mean pose, joint frames aligned with the world there)");
  }
  return out;
}

PreparedClip preprocess_file(const std::string& path, const PreprocessOptions& options) {
  PreparedClip prepared = preprocess(read_clip(path), path, options);
  if (!prepared.report.accepted()) throw InputError(path, 0, "rejected by preprocessing: " + prepared.report.rejection);
  return prepared;
}

double face_forward_at_start(Features& features, const Skeleton& skeleton) {
  if (features.joint_count != skeleton.joint_count()) {
    throw std::invalid_argument("face_forward_at_start: the features have " + std::to_string(features.joint_count) +
                                " joints, the skeleton " + std::to_string(skeleton.joint_count()));
  }
  if (features.frame_count == 0) return 0.0;
  Features first;  // frame 0 alone: its pose is all the rule reads
  first.frame_count = 1;
  first.joint_count = features.joint_count;
  first.fps = features.fps;
  first.start_xz = features.start_xz;
  first.data.assign(features.data.begin(), features.data.begin() + features.joint_count * kFeatureSize);
  const Pose pose = forward_kinematics(skeleton, decode_features(skeleton, first));
  Vec3 forward;
  if (!forward_from_sides(skeleton, pose, forward) && !forward_from_head(skeleton, pose, forward)) return 0.0;
  const double angle = -std::atan2(forward.x(), forward.z());  // turns forward onto +Z
  turn_body(features, angle);
  return angle;
}

}  // namespace nec

// Rig augmentation: rest-pose reset, bone-length scaling, joint removal and
// bone subdivision. Each keeps the motion of the joints it keeps.
#include "nec/corpus/augment.h"

#include "nec/motion/kinematics.h"
#include "nec/motion/names.h"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace nec {
namespace {

constexpr double kZeroLength = 1e-9;

// Lists the joints depth-first, as a BVH file does.
Clip depth_first(Clip clip) {
  const std::vector<int> order = clip.skeleton.depth_first_order();
  bool identity = true;
  for (int i = 0; i < static_cast<int>(order.size()); ++i) identity = identity && order[i] == i;
  if (!identity) permute_joints(clip, order);
  return clip;
}

bool is_zero(const Vec3& v, double scale) { return v.norm() <= kZeroLength * std::max(scale, 1.0); }

// True when joint j's translation is zero in every frame.
bool always_at_parent(const Clip& clip, int j, double scale) {
  if (!is_zero(clip.skeleton.offsets[j], scale)) return false;
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    if (!is_zero(clip.motion.translation(t, j), scale)) return false;
  }
  return true;
}

bool has_end_site(const Skeleton& s, int joint) {
  return std::any_of(s.end_sites.begin(), s.end_sites.end(), [&](const EndSite& e) { return e.parent == joint; });
}

// Rebuilds a clip without joint `removed`; `reparent` gives the new parent of
// each of its children. Motion values are supplied by the caller afterwards.
Clip without_joint(const Clip& clip, int removed, std::vector<int>& new_index) {
  const Skeleton& s = clip.skeleton;
  new_index.assign(s.joint_count(), -1);
  Clip out;
  for (int j = 0; j < s.joint_count(); ++j) {
    if (j == removed) continue;
    int parent = s.parents[j];
    if (parent == removed) parent = s.parents[removed];
    new_index[j] = out.skeleton.add_joint(s.names[j], parent < 0 ? -1 : new_index[parent], s.offsets[j], s.channels[j]);
  }
  for (EndSite site : s.end_sites) {
    if (site.parent == removed) continue;
    site.parent = new_index[site.parent];
    out.skeleton.end_sites.push_back(site);
  }
  out.motion = Motion::rest(out.skeleton, clip.motion.frame_count, clip.motion.fps);
  for (int t = 0; t < clip.motion.frame_count; ++t) {
    for (int j = 0; j < s.joint_count(); ++j) {
      if (new_index[j] < 0) continue;
      out.motion.rotation(t, new_index[j]) = clip.motion.rotation(t, j);
      out.motion.translation(t, new_index[j]) = clip.motion.translation(t, j);
    }
  }
  return out;
}

std::string unique_name(const Skeleton& s, const std::string& base) {
  std::string name = base;
  for (int k = 2; s.find(name) >= 0; ++k) name = base + std::to_string(k);
  return name;
}

}  // namespace

Clip reset_rest_pose_to_frame(const Clip& clip, int frame) {
  const Skeleton& s = clip.skeleton;
  const Motion& m = clip.motion;
  if (frame < 0 || frame >= m.frame_count) throw std::out_of_range("reset_rest_pose_to_frame: no such frame");
  const Pose pose = forward_kinematics(s, m);
  Clip out = clip;
  out.warnings.clear();
  // New offsets: the reference frame's bones in world axes (C.1 eq. 3).
  for (int j = 1; j < s.joint_count(); ++j) out.skeleton.offsets[j] = pose.rotation(frame, s.parents[j]) * s.offsets[j];
  for (EndSite& site : out.skeleton.end_sites) site.offset = pose.rotation(frame, site.parent) * site.offset;
  for (int t = 0; t < m.frame_count; ++t) {
    // New global rotation = old global * (old global at the reference frame)^-1 (eq. 4).
    auto new_global = [&](int j) { return pose.rotation(t, j) * pose.rotation(frame, j).conjugate(); };
    out.motion.rotation(t, 0) = new_global(0).normalized();
    for (int j = 1; j < s.joint_count(); ++j) {
      const int p = s.parents[j];
      out.motion.rotation(t, j) = (new_global(p).conjugate() * new_global(j)).normalized();
      out.motion.translation(t, j) = pose.rotation(frame, p) * m.translation(t, j);
    }
  }
  return out;
}

Clip reset_rest_pose(const Clip& clip, SplitMix64& rng) {
  return reset_rest_pose_to_frame(clip, rng.integer(0, std::max(0, clip.motion.frame_count - 1)));
}

std::vector<std::string> body_parts(const Skeleton& skeleton, const std::vector<std::string>& canonical_names) {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> kParts = {
      {"tail", {"tail"}},
      {"wing", {"wing", "feather"}},
      {"fin", {"fin", "flipper"}},
      {"head", {"head", "jaw", "eye", "ear", "nose", "mouth", "beak", "horn"}},
      {"neck", {"neck"}},
      {"arm", {"arm", "hand", "shoulder", "finger", "thumb"}},
      {"leg", {"leg", "foot", "toe", "knee"}},
      {"spine", {"spine", "chest", "hips", "back", "body", "torso"}},
  };
  std::vector<std::string> parts(skeleton.joint_count(), "other");
  for (int j = 0; j < skeleton.joint_count(); ++j) {
    const std::string& name = j < static_cast<int>(canonical_names.size()) ? canonical_names[j] : skeleton.names[j];
    bool found = false;
    for (const auto& [part, words] : kParts) {
      for (const std::string& w : words) {
        if (name.find(w) != std::string::npos) {
          parts[j] = part;
          found = true;
          break;
        }
      }
      if (found) break;
    }
    // Unnamed joints ("joint12") belong to their parent's part.
    if (!found && j > 0) parts[j] = parts[skeleton.parents[j]];
  }
  return parts;
}

Clip scale_bone_lengths(const Clip& clip, const std::vector<std::string>& canonical_names, SplitMix64& rng,
                        double min_factor, double max_factor) {
  const std::vector<std::string> parts = body_parts(clip.skeleton, canonical_names);
  // One factor per part, drawn in a fixed order so a seed gives the same rig.
  std::map<std::string, double> factor;
  for (const std::string& part : parts) factor.emplace(part, 0.0);
  for (auto& [part, value] : factor) value = rng.uniform(min_factor, max_factor);
  Clip out = clip;
  out.warnings.clear();
  for (int j = 1; j < clip.skeleton.joint_count(); ++j) {
    const double f = factor[parts[j]];
    out.skeleton.offsets[j] *= f;
    for (int t = 0; t < clip.motion.frame_count; ++t) out.motion.translation(t, j) *= f;
  }
  for (EndSite& site : out.skeleton.end_sites) site.offset *= factor[parts[site.parent]];
  // Stride follows leg length: the root path scales with the legs.
  const auto legs = factor.find("leg");
  if (legs != factor.end()) {
    for (int t = 0; t < clip.motion.frame_count; ++t) out.motion.translation(t, 0) *= legs->second;
    out.skeleton.offsets[0] *= legs->second;
  }
  return out;
}

std::vector<int> removable_joints(const Skeleton& skeleton) {
  // Static test on offsets; remove_joint re-checks per-frame translations.
  const auto children = skeleton.children_lists();
  const double scale = skeleton.diameter();
  std::vector<int> out;
  for (int j = 1; j < skeleton.joint_count(); ++j) {
    const bool leaf = children[j].empty();
    const bool children_at_joint =
        !leaf && !has_end_site(skeleton, j) &&
        std::all_of(children[j].begin(), children[j].end(), [&](int c) { return is_zero(skeleton.offsets[c], scale); });
    const int p = skeleton.parents[j];
    const bool merges_into_parent =
        is_zero(skeleton.offsets[j], scale) && children[p].size() == 1 && !has_end_site(skeleton, p);
    if (leaf || children_at_joint || merges_into_parent) out.push_back(j);
  }
  return out;
}

Clip remove_joint(const Clip& clip, int joint) {
  const Skeleton& s = clip.skeleton;
  if (joint <= 0 || joint >= s.joint_count()) throw std::invalid_argument("remove_joint: not a removable joint index");
  const auto children = s.children(joint);
  const double scale = s.diameter();
  const int p = s.parents[joint];
  std::vector<int> new_index;
  if (children.empty()) {
    // A distal joint: drop it; its parent keeps the tip as an end site.
    Clip out = without_joint(clip, joint, new_index);
    if (s.children(p).size() == 1 && !has_end_site(s, p)) out.skeleton.end_sites.push_back({new_index[p], s.offsets[joint]});
    return depth_first(std::move(out));
  }
  const bool children_at_joint =
      !has_end_site(s, joint) &&
      std::all_of(children.begin(), children.end(), [&](int c) { return always_at_parent(clip, c, scale); });
  if (children_at_joint) {
    // Children sit on the joint: they take its place, composing its rotation.
    Clip out = without_joint(clip, joint, new_index);
    for (int t = 0; t < clip.motion.frame_count; ++t) {
      for (int c : children) {
        out.motion.rotation(t, new_index[c]) = (clip.motion.rotation(t, joint) * clip.motion.rotation(t, c)).normalized();
        out.motion.translation(t, new_index[c]) = clip.motion.translation(t, joint);
      }
    }
    for (int c : children) out.skeleton.offsets[new_index[c]] = s.offsets[joint];
    return depth_first(std::move(out));
  }
  if (always_at_parent(clip, joint, scale) && s.children(p).size() == 1 && !has_end_site(s, p)) {
    // A zero-length bone that is its parent's only child: the parent absorbs it.
    Clip out = without_joint(clip, joint, new_index);
    for (int t = 0; t < clip.motion.frame_count; ++t) {
      out.motion.rotation(t, new_index[p]) = (clip.motion.rotation(t, p) * clip.motion.rotation(t, joint)).normalized();
    }
    for (const EndSite& site : s.end_sites) {
      if (site.parent == joint) out.skeleton.end_sites.push_back({new_index[p], site.offset});
    }
    return depth_first(std::move(out));
  }
  throw std::invalid_argument("remove_joint: joint '" + s.names[joint] +
                              "' cannot be removed without moving the joints below it");
}

Clip remove_joints(const Clip& clip, SplitMix64& rng, double fraction) {
  Clip out = clip;
  out.warnings.clear();
  const int wanted = std::max(1, static_cast<int>(fraction * clip.skeleton.joint_count()));
  for (int removed = 0; removed < wanted; ++removed) {
    std::vector<int> candidates = removable_joints(out.skeleton);
    // Keep at least two joints; per-frame checks may still refuse a candidate.
    rng.shuffle(candidates);
    bool done = false;
    for (int j : candidates) {
      if (out.skeleton.joint_count() <= 2) break;
      try {
        out = remove_joint(out, j);
        done = true;
        break;
      } catch (const std::invalid_argument&) {
      }
    }
    if (!done) break;
  }
  return out;
}

Clip subdivide_bone(const Clip& clip, int joint, double fraction) {
  const Skeleton& s = clip.skeleton;
  if (joint <= 0 || joint >= s.joint_count()) throw std::invalid_argument("subdivide_bone: joint must be a non-root joint");
  if (!(fraction > 0.0 && fraction < 1.0)) throw std::invalid_argument("subdivide_bone: fraction must be in (0, 1)");
  Clip out = clip;
  out.warnings.clear();
  const int inserted = out.skeleton.add_joint(unique_name(s, s.names[joint] + "_sub"), s.parents[joint],
                                              fraction * s.offsets[joint],
                                              ChannelLayout::rotations(s.channels[joint].euler_order()));
  out.skeleton.parents[joint] = inserted;
  out.skeleton.offsets[joint] = (1.0 - fraction) * s.offsets[joint];
  Motion m = Motion::rest(out.skeleton, clip.motion.frame_count, clip.motion.fps);
  for (int t = 0; t < m.frame_count; ++t) {
    for (int j = 0; j < s.joint_count(); ++j) {
      m.rotation(t, j) = clip.motion.rotation(t, j);
      m.translation(t, j) = clip.motion.translation(t, j);
    }
    m.translation(t, inserted) = fraction * clip.motion.translation(t, joint);
    m.translation(t, joint) = (1.0 - fraction) * clip.motion.translation(t, joint);
  }
  out.motion = std::move(m);
  // The inserted joint is listed last; list it before its child, as BVH does.
  permute_joints(out, out.skeleton.depth_first_order());
  return out;
}

Clip subdivide_bones(const Clip& clip, SplitMix64& rng, double fraction) {
  Clip out = clip;
  out.warnings.clear();
  const int wanted = std::max(1, static_cast<int>(fraction * clip.skeleton.joint_count()));
  for (int k = 0; k < wanted; ++k) {
    std::vector<int> candidates;
    for (int j = 1; j < out.skeleton.joint_count(); ++j) {
      if (out.skeleton.offsets[j].norm() > kZeroLength) candidates.push_back(j);
    }
    if (candidates.empty()) break;
    const int joint = candidates[rng.below(candidates.size())];
    out = subdivide_bone(out, joint, rng.uniform(0.3, 0.7));
  }
  return out;
}

std::string to_string(AugmentKind kind) {
  switch (kind) {
    case AugmentKind::RestPose: return "rest";
    case AugmentKind::BoneLength: return "length";
    case AugmentKind::JointRemoval: return "remove";
    case AugmentKind::Subdivision: return "subdivide";
  }
  throw std::invalid_argument("to_string: unknown AugmentKind");
}

AugmentKind augment_kind_from_string(const std::string& name) {
  for (AugmentKind kind : {AugmentKind::RestPose, AugmentKind::BoneLength, AugmentKind::JointRemoval, AugmentKind::Subdivision}) {
    if (to_string(kind) == name) return kind;
  }
  throw std::invalid_argument("unknown augmentation '" + name + "' (known: rest, length, remove, subdivide)");
}

Clip augment(const Clip& clip, AugmentKind kind, const std::vector<std::string>& canonical_names, SplitMix64& rng) {
  switch (kind) {
    case AugmentKind::RestPose:
      return reset_rest_pose(clip, rng);
    case AugmentKind::BoneLength:
      return scale_bone_lengths(clip, canonical_names, rng);
    case AugmentKind::JointRemoval:
      return remove_joints(clip, rng);
    case AugmentKind::Subdivision:
      return subdivide_bones(clip, rng);
  }
  throw std::invalid_argument("augment: unknown kind");
}

}  // namespace nec

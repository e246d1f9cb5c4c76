// Skeletons of dataset caches for OwO pretraining: labels, hold-out split, rig augmentation.
#include "nec/owo/skeleton_set.h"

#include "nec/corpus/augment.h"
#include "nec/motion/names.h"
#include "nec/train/config_fields.h"

#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace nec::owo {
namespace {

// Words of a source path, split at / \ _ - . and spaces: "zoo/c004_spider/walk.bvh" -> zoo c004 spider walk bvh.
std::vector<std::string> path_words(const std::string& path) {
  std::vector<std::string> words;
  std::string word;
  for (const char c : path) {
    if (c == '/' || c == '\\' || c == '_' || c == '-' || c == '.' || c == ' ') {
      if (!word.empty()) words.push_back(word);
      word.clear();
    } else {
      word += c;
    }
  }
  if (!word.empty()) words.push_back(word);
  return words;
}

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("AugmentOptions: " + message);
}

bool chance(SplitMix64& rng, double probability) { return probability > 0.0 && rng.chance(probability); }

}  // namespace

std::vector<PretrainSkeleton> skeletons_from_cache(const DatasetCache& cache, int poses_per_skeleton, uint64_t seed) {
  const int count = static_cast<int>(cache.skeletons.size());
  std::vector<PretrainSkeleton> out(count);
  std::vector<std::vector<int>> train_clips(count), other_clips(count);
  std::vector<std::set<std::string>> labels(count);
  for (int i = 0; i < cache.clip_count(); ++i) {
    const CacheClip& clip = cache.clips[i];
    (clip.split == Split::Train ? train_clips : other_clips)[clip.skeleton].push_back(i);
    std::set<std::string>& mine = labels[clip.skeleton];
    mine.insert(clip.dataset);
    mine.insert(clip.source);
    for (std::string& word : path_words(clip.source)) mine.insert(std::move(word));
  }
  std::vector<int> held;
  try {
    held = held_out_skeletons(cache, cache.options.split);
  } catch (const std::invalid_argument&) {
    held.clear();  // a pattern of the cache that matches nothing holds nothing out
  }
  for (int s = 0; s < count; ++s) {
    const CachedSkeleton& cached = cache.skeletons[s];
    PretrainSkeleton& p = out[s];
    p.name = cached.name;
    p.hash = cached.hash;
    p.group = "train";
    p.skeleton = cached.skeleton;
    p.canonical_names = cached.canonical_names;
    p.held_out_by_cache = std::find(held.begin(), held.end(), s) != held.end();
    labels[s].insert(cached.name);
    labels[s].insert(cached.hash);
    labels[s].erase("");
    p.labels.assign(labels[s].begin(), labels[s].end());

    // Poses for rest-pose augmentation, from training clips when there are any.
    const std::vector<int>& clips = train_clips[s].empty() ? other_clips[s] : train_clips[s];
    const int poses = clips.empty() ? 0 : std::max(0, poses_per_skeleton);
    const int joints = cached.skeleton.joint_count();
    Motion motion = Motion::rest(cached.skeleton, poses, cache.fps);
    std::map<int, Clip> decoded;  // clip index -> decoded clip, only those used
    for (int k = 0; k < poses; ++k) {
      const int clip_index = clips[static_cast<size_t>(k) % clips.size()];
      auto found = decoded.find(clip_index);
      if (found == decoded.end()) found = decoded.emplace(clip_index, cache.clip(clip_index)).first;
      const Motion& source = found->second.motion;
      const int frame = static_cast<int>(mix64(seed ^ mix64(static_cast<uint64_t>(s) * 1000003u + k)) %
                                         static_cast<uint64_t>(source.frame_count));
      for (int j = 0; j < joints; ++j) {
        motion.rotation(k, j) = source.rotation(frame, j);
        motion.translation(k, j) = source.translation(frame, j);
      }
    }
    p.poses = std::move(motion);
  }
  return out;
}

bool matches_hold_out(const PretrainSkeleton& skeleton, const std::string& pattern) {
  for (const std::string& label : skeleton.labels) {
    if (wildcard_match(pattern, label)) return true;
  }
  return false;
}

SkeletonSet split_skeleton_set(const std::vector<PretrainSkeleton>& skeletons, const HoldOut& hold_out) {
  // Merge duplicates by hash.
  std::vector<PretrainSkeleton> unique;
  std::unordered_map<std::string, size_t> by_hash;
  for (const PretrainSkeleton& s : skeletons) {
    const auto found = by_hash.find(s.hash);
    if (found == by_hash.end()) {
      by_hash.emplace(s.hash, unique.size());
      unique.push_back(s);
      continue;
    }
    PretrainSkeleton& first = unique[found->second];
    std::set<std::string> labels(first.labels.begin(), first.labels.end());
    labels.insert(s.labels.begin(), s.labels.end());
    first.labels.assign(labels.begin(), labels.end());
    first.held_out_by_cache = first.held_out_by_cache || s.held_out_by_cache;
  }

  SkeletonSet set;
  std::vector<bool> used(hold_out.patterns.size(), false);
  for (PretrainSkeleton& s : unique) {
    std::string group;
    for (size_t p = 0; p < hold_out.patterns.size(); ++p) {
      if (!matches_hold_out(s, hold_out.patterns[p])) continue;
      used[p] = true;
      if (group.empty()) group = hold_out.patterns[p];
    }
    if (group.empty() && hold_out.cache_held_out && s.held_out_by_cache) group = "cache test split";
    if (group.empty()) {
      s.group = "train";
      set.train.push_back(std::move(s));
    } else {
      s.group = group;
      set.held_out.push_back(std::move(s));
    }
  }
  for (size_t p = 0; p < hold_out.patterns.size(); ++p) {
    if (!used[p]) set.unmatched_patterns.push_back(hold_out.patterns[p]);
  }
  return set;
}

void visit_fields(train::ConfigVisitor& v, AugmentOptions& c) {
  v.field("probability", c.probability, "chance that a sample is augmented at all");
  v.field("rest_pose", c.rest_pose, "chance of a rest pose taken from one of its poses");
  v.field("bone_length", c.bone_length, "chance of bone lengths scaled by body part");
  v.field("min_bone_factor", c.min_bone_factor, "smallest bone length factor");
  v.field("max_bone_factor", c.max_bone_factor, "largest bone length factor");
  v.field("joint_removal", c.joint_removal, "chance of removing distal or zero-length joints");
  v.field("subdivision", c.subdivision, "chance of inserting joints inside bones");
  v.field("joint_fraction", c.joint_fraction, "share of joints removed or inserted");
}

void AugmentOptions::validate() const {
  for (const auto& [name, value] : {std::pair<const char*, double>{"probability", probability},
                                    {"rest_pose", rest_pose},
                                    {"bone_length", bone_length},
                                    {"joint_removal", joint_removal},
                                    {"subdivision", subdivision}}) {
    require(value >= 0.0 && value <= 1.0, std::string(name) + " must be in [0, 1], got " + std::to_string(value));
  }
  require(min_bone_factor > 0.0 && min_bone_factor <= max_bone_factor,
          "bone factors must satisfy 0 < min_bone_factor <= max_bone_factor");
  require(joint_fraction > 0.0 && joint_fraction <= 0.5, "joint_fraction must be in (0, 0.5]");
}

AugmentedSkeleton augment_skeleton(const PretrainSkeleton& skeleton, const AugmentOptions& options, SplitMix64& rng) {
  AugmentedSkeleton out{skeleton.skeleton, skeleton.canonical_names};
  if (!chance(rng, options.probability)) return out;
  Clip clip{skeleton.skeleton, Motion::rest(skeleton.skeleton, 1, skeleton.poses.fps), {}};
  bool changed = false;
  if (skeleton.poses.frame_count > 0 && chance(rng, options.rest_pose)) {
    const int frame = rng.integer(0, skeleton.poses.frame_count - 1);
    const Clip posed = reset_rest_pose_to_frame(Clip{skeleton.skeleton, skeleton.poses, {}}, frame);
    clip = Clip{posed.skeleton, Motion::rest(posed.skeleton, 1, skeleton.poses.fps), {}};
    changed = true;
  }
  if (chance(rng, options.bone_length)) {
    clip = scale_bone_lengths(clip, skeleton.canonical_names, rng, options.min_bone_factor, options.max_bone_factor);
    changed = true;
  }
  // Joint changes last: the canonical names above still match the joints.
  if (chance(rng, options.joint_removal) && !removable_joints(clip.skeleton).empty() && clip.skeleton.joint_count() > 2) {
    clip = remove_joints(clip, rng, options.joint_fraction);
    changed = true;
  }
  if (chance(rng, options.subdivision) && clip.skeleton.joint_count() > 1) {
    clip = subdivide_bones(clip, rng, options.joint_fraction);
    changed = true;
  }
  if (!changed) return out;
  out.skeleton = std::move(clip.skeleton);
  out.canonical_names.clear();
  for (const std::string& name : out.skeleton.names) out.canonical_names.push_back(canonical_joint_name(name));
  return out;
}

}  // namespace nec::owo

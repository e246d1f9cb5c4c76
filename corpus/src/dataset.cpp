// The dataset cache in memory: building it from prepared clips (each rig
// stored once, in its canonical rest) and reading clips and features back.
#include "nec/corpus/dataset.h"

#include "dataset_records.h"

#include "nec/motion/hash.h"
#include "nec/corpus/rest_pose.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace nec {

FeatureArray::FeatureArray(std::vector<float> values) {
  auto owned = std::make_shared<const std::vector<float>>(std::move(values));
  data_ = owned->data();
  size_ = owned->size();
  owner_ = std::move(owned);
}


Features DatasetCache::features(int clip) const {
  const CacheClip& c = clips.at(clip);
  Features f;
  f.frame_count = c.frame_count;
  f.joint_count = c.joint_count;
  f.fps = c.fps;
  f.start_xz = c.start_xz;
  const float* data = feature_pointer(clip);
  f.data.assign(data, data + c.feature_size());
  return f;
}

Clip DatasetCache::clip(int clip) const {
  const Skeleton& skeleton = skeleton_of(clip).skeleton;
  return Clip{skeleton, decode_features(skeleton, features(clip)), {}};
}

std::vector<int> DatasetCache::clips_in(Split split) const {
  std::vector<int> out;
  for (int i = 0; i < clip_count(); ++i) {
    if (clips[i].split == split) out.push_back(i);
  }
  return out;
}

int DatasetCache::max_joint_count() const {
  int most = 0;
  for (const CachedSkeleton& s : skeletons) most = std::max(most, s.skeleton.joint_count());
  return most;
}

namespace {

constexpr double kSameOffsetTolerance = 1e-4;  // diameters

// Everything of a skeleton but its offsets.
std::string topology_key(const Skeleton& s, const std::vector<std::string>& canonical_names) {
  std::string key;
  for (int j = 0; j < s.joint_count(); ++j) {
    key += s.names[j] + '\x1f' + canonical_names[j] + '\x1f' + std::to_string(s.parents[j]) + '\x1f';
    for (int c = 0; c < s.channels[j].count; ++c) key += static_cast<char>('0' + static_cast<int>(s.channels[j].channels[c]));
    key += '\x1e';
  }
  for (const EndSite& e : s.end_sites) key += std::to_string(e.parent) + ',';
  return key;
}

// Offsets and end sites within kSameOffsetTolerance of the larger diameter.
bool same_geometry(const Skeleton& a, const Skeleton& b) {
  const double tolerance = kSameOffsetTolerance * std::max({a.diameter(), b.diameter(), 1e-12});
  for (int j = 0; j < a.joint_count(); ++j) {
    if ((a.offsets[j] - b.offsets[j]).norm() > tolerance) return false;
  }
  for (size_t e = 0; e < a.end_sites.size(); ++e) {
    if ((a.end_sites[e].offset - b.end_sites[e].offset).norm() > tolerance) return false;
  }
  return true;
}

// Clips of one rig (same topology, offsets within kSameOffsetTolerance in the file's own joint frames) share one
// canonical rest, the mean pose over all their frames, where preprocess gave each clip its own: one stored skeleton
// per rig, as in the file. Per entry: its rig's rest frames and how many clips the rig has (empty frames for
// rejected entries, entries kept in their file's frames and inconsistent ones, which the caller rejects).
struct RigRest {
  std::vector<Quat> frames;
  int clips = 0;
};

std::vector<RigRest> rig_rest_frames(const std::vector<CacheEntry>& entries) {
  struct Rig {
    Skeleton authored;
    MeanPoseFrames mean;
    int clips = 0;
  };
  std::vector<Rig> rigs;
  std::unordered_map<std::string, std::vector<int>> rigs_by_topology;
  std::vector<int> rig_of(entries.size(), -1);
  for (size_t i = 0; i < entries.size(); ++i) {
    const PreparedClip& p = entries[i].prepared;
    const int joints = p.clip.skeleton.joint_count();
    if (!p.report.accepted() || static_cast<int>(p.normalization.rest_frames.size()) != joints ||
        static_cast<int>(p.canonical_names.size()) != joints || p.clip.motion.joint_count != joints) {
      continue;
    }
    Skeleton authored = reexpress_skeleton(p.clip.skeleton, inverse_frames(p.normalization.rest_frames));
    std::vector<int>& same_topology = rigs_by_topology[topology_key(authored, p.canonical_names)];
    int rig = -1;
    for (int candidate : same_topology) {
      if (same_geometry(rigs[candidate].authored, authored)) {
        rig = candidate;
        break;
      }
    }
    if (rig < 0) {
      rig = static_cast<int>(rigs.size());
      same_topology.push_back(rig);
      rigs.push_back({authored, MeanPoseFrames(authored), 0});
    }
    rigs[rig].mean.add(p.clip.motion, p.normalization.rest_frames);
    ++rigs[rig].clips;
    rig_of[i] = rig;
  }
  std::vector<std::vector<Quat>> frames;
  for (const Rig& rig : rigs) frames.push_back(rig.mean.frames());
  std::vector<RigRest> out(entries.size());
  for (size_t i = 0; i < entries.size(); ++i) {
    if (rig_of[i] >= 0) out[i] = {frames[rig_of[i]], rigs[rig_of[i]].clips};
  }
  return out;
}

}  // namespace

DatasetCache build_cache(const std::vector<CacheEntry>& entries, const CacheOptions& options) {
  options.split.validate();
  DatasetCache cache;
  cache.options = options;
  cache.fps = options.preprocess.target_fps;
  if (cache.fps <= 0.0) {
    cache.fps = 0.0;
    for (const CacheEntry& e : entries) {
      if (e.prepared.report.accepted()) {
        cache.fps = e.prepared.clip.motion.fps;
        break;
      }
    }
  }

  std::unordered_map<std::string, int> clips_per_source;
  for (const CacheEntry& e : entries) {
    if (e.prepared.report.accepted()) ++clips_per_source[e.source];
  }
  std::unordered_map<std::string, int> next_segment;
  std::unordered_set<std::string> ids;
  std::unordered_map<std::string, std::vector<int>> skeletons_by_topology;
  std::unordered_set<std::string> skeleton_names;
  std::unordered_map<std::string, int> unnamed_per_dataset;
  std::vector<float> feature_data;
  const std::vector<RigRest> rig_rests = rig_rest_frames(entries);

  for (size_t index = 0; index < entries.size(); ++index) {
    const CacheEntry& e = entries[index];
    const std::string what = "build_cache: entry " + std::to_string(index) + " ('" + e.source + "'): ";
    const PreparedClip& p = e.prepared;
    if (!p.report.accepted()) {
      cache.rejected.push_back({e.source, e.dataset, p.report.rejection, p.report.changes});
      continue;
    }
    Normalization normalization = p.normalization;
    std::vector<std::string> report = p.report.changes;
    Clip rig_clip;  // the clip in its rig's shared rest
    const RigRest& rig_rest = rig_rests[index];
    if (!rig_rest.frames.empty()) {
      std::vector<Quat> change(rig_rest.frames.size());
      for (size_t j = 0; j < change.size(); ++j) {
        change[j] = (rig_rest.frames[j] * p.normalization.rest_frames[j].conjugate()).normalized();
      }
      rig_clip = reexpress_joint_frames(p.clip, change);
      normalization.rest_frames = rig_rest.frames;
      report.push_back("shares its rig's canonical rest pose (the mean pose of its " + std::to_string(rig_rest.clips) +
                       " clip(s))");
    }
    const Clip& clip = rig_rest.frames.empty() ? p.clip : rig_clip;
    const Skeleton& skeleton = clip.skeleton;
    const Motion& motion = clip.motion;
    if (e.source.empty()) throw std::invalid_argument(what + "has no source file");
    skeleton.validate();
    if (motion.joint_count != skeleton.joint_count()) throw std::invalid_argument(what + "motion and skeleton joint counts differ");
    if (static_cast<int>(p.canonical_names.size()) != skeleton.joint_count()) {
      throw std::invalid_argument(what + "needs one canonical name per joint");
    }
    if (motion.frame_count < 1) throw std::invalid_argument(what + "has no frames");
    if (std::abs(motion.fps - cache.fps) > 1e-6 * cache.fps) {
      throw std::invalid_argument(what + "is at " + std::to_string(motion.fps) + " fps, the corpus at " +
                                  std::to_string(cache.fps));
    }

    CacheClip c;
    c.id = e.id;
    if (c.id.empty()) {
      c.id = e.source;
      if (clips_per_source[e.source] > 1) c.id += "#" + std::to_string(next_segment[e.source]++);
    }
    if (!ids.insert(c.id).second) throw std::invalid_argument(what + "duplicate clip id '" + c.id + "'");

    // Clips of one rig differ in their offsets only by rounding (folded
    // position channels, resampling): same topology and offsets within
    // kSameOffsetTolerance diameters share one stored skeleton.
    std::vector<int>& same_topology = skeletons_by_topology[topology_key(skeleton, p.canonical_names)];
    int stored_index = -1;
    for (int candidate : same_topology) {
      if (same_geometry(cache.skeletons[candidate].skeleton, skeleton)) {
        stored_index = candidate;
        break;
      }
    }
    if (stored_index < 0) {
      const std::string record = detail::serialize_skeleton(skeleton, p.canonical_names);
      CachedSkeleton stored;
      std::string base = e.skeleton_name;
      if (base.empty()) {
        base = e.dataset.empty() ? "skeleton" : e.dataset;
        const int n = ++unnamed_per_dataset[base];
        if (n > 1) base += "-" + std::to_string(n);
      }
      stored.name = base;
      for (int n = 2; skeleton_names.count(stored.name); ++n) stored.name = base + "-" + std::to_string(n);
      skeleton_names.insert(stored.name);
      stored.hash = detail::hex16(fnv1a64(record));
      stored.skeleton = skeleton;
      stored.canonical_names = p.canonical_names;
      stored_index = static_cast<int>(cache.skeletons.size());
      same_topology.push_back(stored_index);
      cache.skeletons.push_back(std::move(stored));
    }

    const Features f = encode_features(skeleton, motion);
    c.source = e.source;
    c.dataset = e.dataset;
    c.skeleton = stored_index;
    c.frame_count = f.frame_count;
    c.joint_count = f.joint_count;
    c.fps = cache.fps;
    c.source_frame = e.source_frame;
    c.captions = e.captions;
    c.normalization = std::move(normalization);
    c.start_xz = f.start_xz;
    c.report = std::move(report);
    c.feature_offset = feature_data.size();
    feature_data.insert(feature_data.end(), f.data.begin(), f.data.end());
    cache.clips.push_back(std::move(c));
  }

  cache.feature_data = FeatureArray(std::move(feature_data));
  const std::vector<Split> splits = assign_splits(cache, options.split);
  for (size_t i = 0; i < splits.size(); ++i) cache.clips[i].split = splits[i];
  return cache;
}


}  // namespace nec

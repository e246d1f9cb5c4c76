// The dataset cache: prepared clips of a whole corpus in one directory that
// loads in well under a second (format: docs/dataset-format.md).
//
//   std::vector<CacheEntry> entries;
//   entries.push_back({preprocess(read_bvh(path), path), path, "dog", {"a dog trots"}});
//   write_cache("cache/", entries, CacheOptions{});            // atomic: all or nothing
//   DatasetCache cache = read_cache("cache/");                 // InputError with a hint on mismatch
//   for (int i : cache.clips_in(Split::Train)) {
//     Features f = cache.features(i);                          // (T, J, 9)
//     Clip c = cache.clip(i);                                  // Motion on the normalized skeleton
//   }
//
// A directory holds manifest.json (format, version, options, skeletons, clips,
// rejected files), features.f32 (every clip's Θ, float32 little-endian,
// concatenated) and skeletons.bin (each distinct skeleton once: clips whose
// skeletons have the same topology and offsets within 1e-4 diameters share the
// first one's record). Clips of one rig share one canonical rest pose, the
// mean pose over all of them (corpus/rest_pose.h), so a rig is stored once, as
// in its file. Splits are assigned per source file, so the clips cut from one
// long take never straddle train and test.
#pragma once

#include "nec/motion/features.h"
#include "nec/corpus/preprocess.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nec {

constexpr const char* kDatasetFormatName = "nec-dataset";
constexpr int kDatasetFormatVersion = 2;  // 2: the canonical rest pose (rest_frames); docs/dataset-format.md

enum class Split { Train, Val, Test };

std::string_view split_name(Split split);  // "train", "val", "test"
std::optional<Split> parse_split(std::string_view name);

// How clips are assigned to train/val/test. Deterministic for a seed and
// independent of the order of the entries.
struct SplitOptions {
  double val_fraction = 0.05;   // share of the clips not held out, e.g. 0.05
  double test_fraction = 0.05;  // share of the clips not held out, e.g. 0.05
  uint64_t seed = 0;            // same seed, same corpus -> same split
  // Skeletons whose every clip goes to test: skeleton names or content hashes,
  // with '*' and '?' wildcards, e.g. {"spider*", "3f2a9c0d11e4b7a8"}.
  std::vector<std::string> held_out_skeletons;
  // Datasets whose skeletons are held out (with every clip of those skeletons,
  // from any dataset), e.g. {"dog"}.
  std::vector<std::string> held_out_datasets;

  // Throws std::invalid_argument when a fraction is outside [0, 1] or they sum above 1.
  void validate() const;
};

// What a cache was made with; recorded in the manifest.
struct CacheOptions {
  PreprocessOptions preprocess;  // the options the entries were prepared with (recorded only)
  SplitOptions split;
};

// One clip to store: a preprocessed clip and what is known about it.
struct CacheEntry {
  PreparedClip prepared;              // output of preprocess(); rejected clips are listed, not stored
  std::string source;                 // source file, e.g. "mann_dog/D1_001_KAN01_001.bvh"; clips of one source share a split
  std::string dataset;                // e.g. "bandai", "dog", "cmu", "zoo"
  std::vector<std::string> captions;  // zero or more, e.g. {"a dog trots forward"}
  std::string id;                     // unique clip id; empty: the source, "#n" appended when a source has several clips
  int source_frame = 0;               // first frame of the clip within its source take (corpus fps), e.g. 1800
  std::string skeleton_name;          // label of the skeleton, e.g. "spider"; empty: the dataset name (+ "-2", "-3", ...)
};

// Read-only floats shared by the copies of a cache: a memory map of
// features.f32 (read_cache) or an owned array (build_cache). Mapping is what
// makes loading fast; the data stays valid after the cache directory is
// replaced (the old file lives on while mapped), not if it is truncated in place.
class FeatureArray {
 public:
  FeatureArray() = default;
  explicit FeatureArray(std::vector<float> values);
  // Maps `floats` little-endian float32 values of `path` (read and byte-swapped
  // on big-endian hosts). Throws InputError when the file cannot be read.
  static FeatureArray map_file(const std::string& path, size_t floats);

  const float* data() const { return data_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const float& operator[](size_t i) const { return data_[i]; }

 private:
  std::shared_ptr<const void> owner_;  // the vector or the mapping
  const float* data_ = nullptr;
  size_t size_ = 0;
};

// A distinct skeleton of the corpus (stored once however many clips use it).
struct CachedSkeleton {
  std::string name;                          // unique label, e.g. "dog" or "bandai-2"
  std::string hash;                          // 16 hex digits: content hash of the stored record
  Skeleton skeleton;                         // normalized (diameter 1), the file's own joint names
  std::vector<std::string> canonical_names;  // (J) canonical joint names, e.g. "left upper leg"
};

// One stored clip; its features live in DatasetCache::feature_data.
struct CacheClip {
  std::string id;                     // unique, e.g. "mann_dog/D1_001_KAN01_001.bvh#3"
  std::string source;                 // source file
  std::string dataset;                // e.g. "dog"
  int skeleton = 0;                   // index into DatasetCache::skeletons
  int frame_count = 0;                // T
  int joint_count = 0;                // J of its skeleton
  double fps = 30.0;                  // the corpus fps
  int source_frame = 0;               // first frame within the source take
  std::vector<std::string> captions;  // zero or more
  Split split = Split::Train;
  Normalization normalization;        // how to get back to the file's units and heading
  std::array<double, 2> start_xz{0.0, 0.0};  // Features::start_xz: root ground position at frame 0
  std::vector<std::string> report;    // preprocessing report lines (what was changed)
  size_t feature_offset = 0;          // index of its first float in DatasetCache::feature_data

  size_t feature_size() const { return static_cast<size_t>(frame_count) * joint_count * kFeatureSize; }
};

// A source file that preprocessing rejected, kept for the report.
struct RejectedFile {
  std::string source;
  std::string dataset;
  std::string reason;                // PreprocessReport::rejection
  std::vector<std::string> report;   // the changes made before the rejection
};

struct DatasetCache {
  std::string directory;                 // where it was read from; empty when built in memory
  double fps = 30.0;                     // corpus fps shared by every clip, e.g. 30
  CacheOptions options;                  // what it was made with
  std::vector<CachedSkeleton> skeletons;
  std::vector<CacheClip> clips;
  std::vector<RejectedFile> rejected;
  FeatureArray feature_data;             // every clip's (T, J, 9) Θ, concatenated in clip order

  int clip_count() const { return static_cast<int>(clips.size()); }
  const CachedSkeleton& skeleton_of(int clip) const { return skeletons.at(clips.at(clip).skeleton); }
  // The clip's Θ in place, (T, J, 9) row-major.
  const float* feature_pointer(int clip) const { return feature_data.data() + clips.at(clip).feature_offset; }
  // A copy of the clip's Θ, (T, J, 9).
  Features features(int clip) const;
  // The decoded motion on the clip's normalized skeleton (decode_features).
  Clip clip(int clip) const;
  // Indices of the clips in `split`, ascending.
  std::vector<int> clips_in(Split split) const;
  // Most joints of any skeleton (0 for an empty cache).
  int max_joint_count() const;
};

// Builds the cache in memory: encodes features, deduplicates skeletons, lists
// rejected entries and assigns splits. Throws std::invalid_argument on
// inconsistent entries (joint counts, canonical names, fps differing from the
// corpus fps, duplicate ids, empty clips).
DatasetCache build_cache(const std::vector<CacheEntry>& entries, const CacheOptions& options);

// Writes `cache` to directory `dir` through a temporary sibling directory and
// a rename, replacing an existing cache there. Never leaves a half-written
// cache. Throws InputError when `dir` exists and is not a dataset cache,
// std::runtime_error on I/O failure.
void save_cache(const DatasetCache& cache, const std::string& dir);

// build_cache + save_cache.
void write_cache(const std::string& dir, const std::vector<CacheEntry>& entries, const CacheOptions& options);

// Reads a cache written by save_cache. Checks the format name and version and
// every size; throws InputError naming the file, the problem and "re-run nec
// prepare" when anything does not match.
DatasetCache read_cache(const std::string& dir);

// The split of every clip of `cache` (one per clip, in clip order): clips of
// held-out skeletons go to test; the other source files are ordered by a hash
// of (seed, source) and filled into test, then val, until each reaches its
// fraction of the clips; the rest is train.
std::vector<Split> assign_splits(const DatasetCache& cache, const SplitOptions& options);

// Indices of the skeletons that `options` holds out.
std::vector<int> held_out_skeletons(const DatasetCache& cache, const SplitOptions& options);

// A hash of the cache's manifest (and clip count): files derived from a cache
// (retrieval indexes, GPT token sets) are keyed by it. A cache built in memory
// hashes its clip count alone.
uint64_t cache_key(const DatasetCache& cache);

// Shell-style wildcard match: '*' any run of characters, '?' one character.
bool wildcard_match(std::string_view pattern, std::string_view text);

}  // namespace nec

// Batches for training and evaluation from a DatasetCache: random crops,
// shuffling per epoch, on-the-fly rig augmentation, zero padding and masks.
// Plain arrays, no torch: the model code wraps them with torch::from_blob.
//
//   DatasetCache cache = read_cache("cache/");
//   BatchOptions options;  options.batch_size = 32;  options.crop_frames = 64;
//   options.augment_probability = 0.5;
//   BatchLoader loader(cache, Split::Train, options);
//   for (int step = 0; step < steps; ++step) {
//     Batch b = loader.next();                    // moves to the next epoch by itself
//     // b.features (B, T, Jmax, 9), b.joint_mask (B, Jmax), b.frame_mask (B, T) ...
//   }
//
// Everything random (epoch order, crop starts, captions, augmentation) is a
// function of (seed, epoch, position in the epoch): batch(e, i) is the same
// whichever batches were made before it.
#pragma once

#include "nec/corpus/augment.h"
#include "nec/corpus/dataset.h"

#include <cstdint>
#include <string>
#include <vector>

namespace nec {

// One process's share of a global batch of `items` in data-parallel training:
// a contiguous range, the first `items % world_size` ranks taking one more.
struct BatchShare {
  int64_t begin = 0;  // first item of the share
  int64_t count = 0;  // its items (0 when items < world_size for the last ranks)
};
BatchShare share_of(int64_t items, int rank, int world_size);

struct BatchOptions {
  int batch_size = 32;              // B (the last batch of an epoch may be smaller unless drop_last)
  int crop_frames = 64;             // T, e.g. 64; shorter clips are padded and masked; 0 = whole clips, T = longest in the batch
  uint64_t seed = 0;                // same seed, same batches
  bool shuffle = true;              // a new clip order every epoch; false: clip order
  bool drop_last = false;           // skip the last, smaller batch of an epoch
  int joint_buckets = 0;            // > 0: batches of similar joint counts (less padding): each run of
                                    // joint_buckets batches of the shuffled order is sorted by joint count,
                                    // then the epoch's batches are shuffled; e.g. 16
  double augment_probability = 0.0; // chance that an item's rig is augmented, e.g. 0.5
  std::vector<AugmentKind> augment_kinds{AugmentKind::RestPose, AugmentKind::BoneLength, AugmentKind::JointRemoval,
                                         AugmentKind::Subdivision};  // one is drawn uniformly per augmented item
  int shard_rank = 0;               // data-parallel: a batch holds only this rank's share_of its B items,
  int shard_count = 1;              // of shard_count ranks; each item is the one a single process draws

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

// One batch. Row-major arrays; shapes in the comments; padding is zero (parents -1).
struct Batch {
  int size = 0;        // B, items (of this rank's share when sharded)
  int global_size = 0; // items of the whole batch over every shard (= size unsharded)
  int frames = 0;      // T, frames per item (crop_frames, or the longest clip when crop_frames = 0)
  int max_joints = 0;  // Jmax, most joints of any item (after augmentation)

  std::vector<float> features;      // (B, T, Jmax, 9) Θ, each item turned to its clip's start heading
                                    // (turn_to_heading); zero outside frame_mask × joint_mask
  std::vector<uint8_t> joint_mask;  // (B, Jmax) 1 for the item's joints
  std::vector<uint8_t> frame_mask;  // (B, T) 1 for the item's frames
  std::vector<int32_t> parents;     // (B, Jmax) parent index; -1 for roots and padding
  std::vector<float> offsets;       // (B, Jmax, 3) rest offsets (normalized units); zero for padding

  std::vector<int> joint_counts;    // (B) joints of each item, = sum of its joint_mask row
  std::vector<int> frame_counts;    // (B) real frames of each item, = sum of its frame_mask row
  std::vector<int> clip_indices;    // (B) index into DatasetCache::clips
  std::vector<int> crop_starts;     // (B) first frame of the crop within the clip
  std::vector<uint8_t> augmented;   // (B) 1 when the item's rig was augmented
  std::vector<std::string> captions;                      // (B) one of the clip's captions, "" when it has none
  std::vector<std::vector<std::string>> canonical_names;  // (B) (J_b) canonical joint names
  std::vector<Skeleton> skeletons;                        // (B) the item's skeleton (augmented when augmented)

  float feature(int item, int frame, int joint, int k) const {
    return features[((static_cast<size_t>(item) * frames + frame) * max_joints + joint) * kFeatureSize + k];
  }
};

// Crop of a clip's Θ as a valid Θ of its own: frames [begin, begin + count),
// with frame 0's root displacement replaced by (0, root height, 0) as
// encode_features writes it. (count, J, 9)
Features crop_features(const DatasetCache& cache, int clip, int begin, int count);
// crop_features turned to the heading of its clip's frame 0 (turn_to_heading),
// where preprocessing made the body face +Z: a training crop as batches hold it.
Features crop_at_start_heading(const DatasetCache& cache, int clip, int begin, int count);

class BatchLoader {
 public:
  // The loader keeps a reference to `cache`: it must outlive the loader.
  // Throws InputError (naming the cache) when the split has no clips.
  BatchLoader(const DatasetCache& cache, Split split, BatchOptions options);
  // Over an explicit list of clip indices.
  BatchLoader(const DatasetCache& cache, std::vector<int> clip_indices, BatchOptions options);

  int clip_count() const { return static_cast<int>(clips_.size()); }
  int batches_per_epoch() const;
  // Clip indices in the order epoch `epoch` visits them.
  std::vector<int> epoch_order(int epoch) const;
  // Batch `index` (0 <= index < batches_per_epoch()) of epoch `epoch`. Safe
  // to call from several threads at once (e.g. a prefetching pool); next() is not.
  Batch batch(int epoch, int index) const;
  // The next batch of the stream: batch 0 of epoch 0, 1, ..., then epoch 1.
  Batch next();
  // Where next() continues from, e.g. to resume training.
  void seek(int epoch, int index);
  int epoch() const { return epoch_; }
  int index() const { return index_; }

 private:
  Batch assemble(const std::vector<int>& order, int epoch, int index) const;

  const DatasetCache& cache_;
  std::vector<int> clips_;
  BatchOptions options_;
  int epoch_ = 0;
  int index_ = 0;
  int order_epoch_ = -1;     // epoch whose order is in order_
  std::vector<int> order_;
};

}  // namespace nec

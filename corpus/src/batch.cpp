// Batch loader: crops, shuffling, rig augmentation and padding over a DatasetCache.
#include "nec/corpus/batch.h"

#include "nec/motion/error.h"
#include "nec/motion/names.h"
#include "nec/motion/random.h"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace nec {

namespace {

constexpr uint64_t kOrderStream = ~uint64_t{0};  // stream of the epoch order; items use their position
constexpr uint64_t kBucketStream = ~uint64_t{1};  // stream of the batch order when bucketing by joint count

uint64_t stream_seed(uint64_t seed, int epoch, uint64_t stream) {
  return mix64(mix64(mix64(seed) ^ static_cast<uint64_t>(epoch)) ^ stream);
}

// One item before padding.
struct Item {
  int clip = 0;
  int crop_start = 0;
  bool augmented = false;
  Features features;  // (T_b, J_b, 9)
  Skeleton skeleton;
  std::vector<std::string> canonical_names;  // (J_b)
  std::string caption;
};

// Canonical names of an augmented skeleton: kept joints keep theirs; joints
// that augmentation inserted get canonical_joint_name of their own name.
std::vector<std::string> augmented_canonical_names(const Skeleton& original, const std::vector<std::string>& canonical,
                                                   const Skeleton& augmented) {
  std::unordered_map<std::string, int> index;
  for (int j = 0; j < original.joint_count(); ++j) index.emplace(original.names[j], j);
  std::vector<std::string> out;
  out.reserve(augmented.names.size());
  for (const std::string& name : augmented.names) {
    const auto found = index.find(name);
    out.push_back(found != index.end() ? canonical[found->second] : canonical_joint_name(name));
  }
  return out;
}

}  // namespace

BatchShare share_of(int64_t items, int rank, int world_size) {
  if (world_size < 1 || rank < 0 || rank >= world_size || items < 0) {
    throw std::invalid_argument("share_of: rank " + std::to_string(rank) + " of " + std::to_string(world_size));
  }
  const int64_t base = items / world_size, extra = items % world_size;
  return BatchShare{rank * base + std::min<int64_t>(rank, extra), base + (rank < extra ? 1 : 0)};
}

void BatchOptions::validate() const {
  if (batch_size < 1) throw std::invalid_argument("BatchOptions: batch_size must be at least 1, is " + std::to_string(batch_size));
  if (crop_frames < 0) throw std::invalid_argument("BatchOptions: crop_frames must be >= 0, is " + std::to_string(crop_frames));
  if (shard_count < 1 || shard_rank < 0 || shard_rank >= shard_count) {
    throw std::invalid_argument("BatchOptions: shard_rank must be in [0, shard_count), is " + std::to_string(shard_rank) +
                                " of " + std::to_string(shard_count));
  }
  if (joint_buckets < 0) throw std::invalid_argument("BatchOptions: joint_buckets must be >= 0, is " + std::to_string(joint_buckets));
  if (!(augment_probability >= 0.0 && augment_probability <= 1.0)) {
    throw std::invalid_argument("BatchOptions: augment_probability must be in [0, 1], is " + std::to_string(augment_probability));
  }
  if (augment_probability > 0.0 && augment_kinds.empty()) {
    throw std::invalid_argument("BatchOptions: augment_probability > 0 needs at least one augment kind");
  }
}

Features crop_features(const DatasetCache& cache, int clip, int begin, int count) {
  const CacheClip& c = cache.clips.at(clip);
  if (begin < 0 || count < 1 || begin + count > c.frame_count) {
    throw std::out_of_range("crop_features: frames [" + std::to_string(begin) + ", " + std::to_string(begin + count) +
                            ") outside clip '" + c.id + "' of " + std::to_string(c.frame_count) + " frames");
  }
  const size_t frame_floats = static_cast<size_t>(c.joint_count) * kFeatureSize;
  const float* data = cache.feature_pointer(clip);
  Features f;
  f.frame_count = count;
  f.joint_count = c.joint_count;
  f.fps = c.fps;
  f.data.assign(data + begin * frame_floats, data + (begin + count) * frame_floats);
  if (begin == 0) {
    f.start_xz = c.start_xz;
    return f;
  }
  // The heading frame turns about +Y only, so Δy is the height change and
  // the height at `begin` is the sum of Δy up to it.
  double height = 0.0;
  for (int t = 0; t <= begin; ++t) height += data[t * frame_floats + 1];
  f.at(0, 0, 0) = 0.0f;
  f.at(0, 0, 1) = static_cast<float>(height);
  f.at(0, 0, 2) = 0.0f;
  return f;
}

Features crop_at_start_heading(const DatasetCache& cache, int clip, int begin, int count) {
  Features crop = crop_features(cache, clip, begin, count);
  turn_to_heading(crop, root_heading(crop_features(cache, clip, 0, 1), 0));
  return crop;
}

BatchLoader::BatchLoader(const DatasetCache& cache, Split split, BatchOptions options)
    : cache_(cache), clips_(cache.clips_in(split)), options_(std::move(options)) {
  if (clips_.empty()) {
    throw InputError(cache.directory.empty() ? std::string("dataset cache") : cache.directory, 0,
                     "no clips in split '" + std::string(split_name(split)) + "' (see the split options of nec prepare)");
  }
  options_.validate();
  if (options_.drop_last && clip_count() < options_.batch_size) {
    throw std::invalid_argument("BatchLoader: " + std::to_string(clip_count()) + " clips make no full batch of " +
                                std::to_string(options_.batch_size) + " with drop_last");
  }
}

BatchLoader::BatchLoader(const DatasetCache& cache, std::vector<int> clip_indices, BatchOptions options)
    : cache_(cache), clips_(std::move(clip_indices)), options_(std::move(options)) {
  if (clips_.empty()) throw std::invalid_argument("BatchLoader: no clips");
  for (int c : clips_) {
    if (c < 0 || c >= cache.clip_count()) throw std::out_of_range("BatchLoader: clip index " + std::to_string(c) + " out of range");
  }
  options_.validate();
  if (options_.drop_last && clip_count() < options_.batch_size) {
    throw std::invalid_argument("BatchLoader: " + std::to_string(clip_count()) + " clips make no full batch of " +
                                std::to_string(options_.batch_size) + " with drop_last");
  }
}

int BatchLoader::batches_per_epoch() const {
  const int n = clip_count(), b = options_.batch_size;
  return options_.drop_last ? n / b : (n + b - 1) / b;
}

std::vector<int> BatchLoader::epoch_order(int epoch) const {
  std::vector<int> order = clips_;
  if (!options_.shuffle) return order;
  SplitMix64(stream_seed(options_.seed, epoch, kOrderStream)).shuffle(order);
  if (options_.joint_buckets == 0) return order;

  // Sort runs of joint_buckets batches by joint count, then shuffle whole batches.
  const size_t batch = static_cast<size_t>(options_.batch_size);
  const size_t run = batch * static_cast<size_t>(options_.joint_buckets);
  const auto by_joints = [&](int a, int b) { return cache_.clips[a].joint_count < cache_.clips[b].joint_count; };
  for (size_t start = 0; start < order.size(); start += run) {
    std::stable_sort(order.begin() + start, order.begin() + std::min(order.size(), start + run), by_joints);
  }
  const size_t full = order.size() / batch;  // a smaller last batch stays last
  std::vector<size_t> batches(full);
  for (size_t i = 0; i < full; ++i) batches[i] = i;
  SplitMix64(stream_seed(options_.seed, epoch, kBucketStream)).shuffle(batches);
  std::vector<int> shuffled;
  shuffled.reserve(order.size());
  for (size_t b : batches) shuffled.insert(shuffled.end(), order.begin() + b * batch, order.begin() + (b + 1) * batch);
  shuffled.insert(shuffled.end(), order.begin() + full * batch, order.end());
  return shuffled;
}

Batch BatchLoader::batch(int epoch, int index) const {
  if (epoch < 0 || index < 0 || index >= batches_per_epoch()) {
    throw std::out_of_range("BatchLoader::batch: batch " + std::to_string(index) + " of epoch " + std::to_string(epoch) +
                            " (an epoch has " + std::to_string(batches_per_epoch()) + ")");
  }
  return assemble(epoch_order(epoch), epoch, index);
}

Batch BatchLoader::next() {
  if (order_epoch_ != epoch_) {
    order_ = epoch_order(epoch_);
    order_epoch_ = epoch_;
  }
  Batch out = assemble(order_, epoch_, index_);
  if (++index_ == batches_per_epoch()) {
    index_ = 0;
    ++epoch_;
  }
  return out;
}

void BatchLoader::seek(int epoch, int index) {
  if (epoch < 0 || index < 0 || index >= batches_per_epoch()) {
    throw std::out_of_range("BatchLoader::seek: batch " + std::to_string(index) + " of epoch " + std::to_string(epoch));
  }
  epoch_ = epoch;
  index_ = index;
}

Batch BatchLoader::assemble(const std::vector<int>& order, int epoch, int index) const {
  const size_t batch_first = static_cast<size_t>(index) * options_.batch_size;
  const size_t batch_last = std::min(order.size(), batch_first + options_.batch_size);
  const BatchShare share =
      share_of(static_cast<int64_t>(batch_last - batch_first), options_.shard_rank, options_.shard_count);
  const size_t first = batch_first + static_cast<size_t>(share.begin);
  const size_t last = first + static_cast<size_t>(share.count);

  std::vector<Item> items;
  items.reserve(last - first);
  for (size_t position = first; position < last; ++position) {
    Item item;
    item.clip = order[position];
    const CacheClip& c = cache_.clips[item.clip];
    const CachedSkeleton& stored = cache_.skeletons[c.skeleton];
    SplitMix64 random(stream_seed(options_.seed, epoch, position));

    if (!c.captions.empty()) item.caption = c.captions[random.below(c.captions.size())];
    int count = c.frame_count;
    if (options_.crop_frames > 0 && c.frame_count > options_.crop_frames) {
      count = options_.crop_frames;
      item.crop_start = static_cast<int>(random.below(static_cast<uint64_t>(c.frame_count - count + 1)));
    }
    item.features = crop_at_start_heading(cache_, item.clip, item.crop_start, count);
    item.skeleton = stored.skeleton;
    item.canonical_names = stored.canonical_names;

    if (options_.augment_probability > 0.0 && random.uniform() < options_.augment_probability) {
      const AugmentKind kind = options_.augment_kinds[random.below(options_.augment_kinds.size())];
      SplitMix64 rng(random.next());
      const Clip source{stored.skeleton, decode_features(stored.skeleton, item.features), {}};
      Clip changed = augment(source, kind, stored.canonical_names, rng);
      if (changed.motion.frame_count != count) {
        throw std::logic_error("BatchLoader: augmentation changed the frame count of clip '" + c.id + "'");
      }
      item.canonical_names = augmented_canonical_names(stored.skeleton, stored.canonical_names, changed.skeleton);
      item.features = encode_features(changed.skeleton, changed.motion);
      item.skeleton = std::move(changed.skeleton);
      item.augmented = true;
    }
    items.push_back(std::move(item));
  }

  Batch b;
  b.size = static_cast<int>(items.size());
  b.global_size = static_cast<int>(batch_last - batch_first);
  for (const Item& item : items) {
    b.max_joints = std::max(b.max_joints, item.skeleton.joint_count());
    b.frames = std::max(b.frames, item.features.frame_count);
  }
  if (options_.crop_frames > 0) b.frames = options_.crop_frames;
  const size_t B = b.size, T = b.frames, J = b.max_joints;
  b.features.assign(B * T * J * kFeatureSize, 0.0f);
  b.joint_mask.assign(B * J, 0);
  b.frame_mask.assign(B * T, 0);
  b.parents.assign(B * J, -1);
  b.offsets.assign(B * J * 3, 0.0f);

  for (size_t i = 0; i < B; ++i) {
    Item& item = items[i];
    const int joints = item.skeleton.joint_count();
    const int frames = item.features.frame_count;
    const size_t row = static_cast<size_t>(joints) * kFeatureSize;
    for (int t = 0; t < frames; ++t) {
      const float* from = item.features.data.data() + t * row;
      std::copy(from, from + row, b.features.begin() + ((i * T + t) * J) * kFeatureSize);
      b.frame_mask[i * T + t] = 1;
    }
    for (int j = 0; j < joints; ++j) {
      b.joint_mask[i * J + j] = 1;
      b.parents[i * J + j] = item.skeleton.parents[j];
      for (int k = 0; k < 3; ++k) b.offsets[(i * J + j) * 3 + k] = static_cast<float>(item.skeleton.offsets[j][k]);
    }
    b.joint_counts.push_back(joints);
    b.frame_counts.push_back(frames);
    b.clip_indices.push_back(item.clip);
    b.crop_starts.push_back(item.crop_start);
    b.augmented.push_back(item.augmented ? 1 : 0);
    b.captions.push_back(std::move(item.caption));
    b.canonical_names.push_back(std::move(item.canonical_names));
    b.skeletons.push_back(std::move(item.skeleton));
  }
  return b;
}

}  // namespace nec

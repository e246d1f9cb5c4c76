// Batches of clips for training: config fields, loader options, position.
#include "nec/train/clip_batches.h"

#include "nec/corpus/augment.h"
#include "nec/motion/error.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"

#include <stdexcept>

namespace nec::train {

void ClipAugmentConfig::validate() const {
  if (!(probability >= 0 && probability <= 1)) throw std::invalid_argument("probability must be in [0, 1]");
  if (probability > 0 && kinds.empty()) throw std::invalid_argument("kinds is empty");
  for (const std::string& kind : kinds) {
    try {
      augment_kind_from_string(kind);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("kinds: ") + e.what());
    }
  }
}

void visit_fields(ConfigVisitor& v, ClipAugmentConfig& c) {
  v.field("probability", c.probability, "chance that a training clip's rig is augmented");
  v.field("kinds", c.kinds, "the augmentations an augmented clip draws one of (rest, length, remove, subdivide)");
}

void ClipBatchConfig::validate() const {
  if (window_frames < 1) throw std::invalid_argument("data.window_frames must be >= 1");
  if (joint_buckets < 0) throw std::invalid_argument("data.joint_buckets must be >= 0");
  try {
    augment.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("data.augment.") + e.what());
  }
}

void visit_fields(ConfigVisitor& v, ClipBatchConfig& c) {
  v.field("window_frames", c.window_frames, "training crop in frames (a random window of each clip)");
  v.field("joint_buckets", c.joint_buckets,
          "runs of this many batches are sorted by joint count (less padding, one body plan per batch mostly); 0 = off");
  v.object("augment", c.augment, "rig augmentation of the training clips");
}

BatchOptions training_batches(const ClipBatchConfig& data, int64_t batch_size, uint64_t seed, const Communicator* ranks) {
  BatchOptions options;
  options.batch_size = static_cast<int>(batch_size);
  options.crop_frames = static_cast<int>(data.window_frames);
  options.seed = seed;
  options.drop_last = true;
  options.augment_probability = data.augment.probability;
  options.augment_kinds.clear();
  for (const std::string& kind : data.augment.kinds) options.augment_kinds.push_back(augment_kind_from_string(kind));
  options.joint_buckets = static_cast<int>(data.joint_buckets);
  if (ranks != nullptr) {
    options.shard_rank = ranks->rank();
    options.shard_count = ranks->world_size();
  }
  return options;
}

nlohmann::json batch_position(const BatchLoader& loader) { return {{"epoch", loader.epoch()}, {"index", loader.index()}}; }

void seek_batches(BatchLoader& loader, const nlohmann::json& position, const std::string& state_path) {
  const JsonFields fields(state_path, "the training state is damaged; train again into a new --out");
  int64_t epoch = 0, index = 0;
  fields.read(position, "epoch", "data.", epoch);
  fields.read(position, "index", "data.", index);
  try {
    loader.seek(static_cast<int>(epoch), static_cast<int>(index));
  } catch (const std::out_of_range&) {
    throw InputError(state_path, 0,
                     "batch " + std::to_string(index) + " of epoch " + std::to_string(epoch) +
                         " is not in this train split; resume with the same --data, or train into a new --out");
  }
}

}  // namespace nec::train

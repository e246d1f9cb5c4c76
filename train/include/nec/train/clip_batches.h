// What every trainer of clip models (tokenizer, evaluator, generators) shares
// about its batches: the crop, joint-count buckets and rig augmentation of its
// config file, the loader options they make, and the loader's position in a
// training state.
//
//   ClipBatchConfig data;                                          // a config's "data" object
//   BatchLoader loader(cache, clips, training_batches(data, 32, seed, ranks));
//   state.data = batch_position(loader);                           // {"epoch", "index"}
//   seek_batches(loader, state.data, "runs/tat/training.json");    // on resume
#pragma once

#include "nec/corpus/batch.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace nec::train {

class Communicator;
class ConfigVisitor;

// Rig augmentation of the training clips (corpus/augment.h).
struct ClipAugmentConfig {
  double probability = 0.5;  // chance that an item's rig is augmented
  std::vector<std::string> kinds{"rest", "length", "remove", "subdivide"};  // one drawn uniformly per augmented item

  // Throws std::invalid_argument naming the bad field (without the "augment." prefix).
  void validate() const;
};
void visit_fields(ConfigVisitor& v, ClipAugmentConfig& c);

// How training batches are cut from the cache.
struct ClipBatchConfig {
  int64_t window_frames = 64;  // training crop T, e.g. 64
  int64_t joint_buckets = 16;  // batches of similar joint counts (BatchOptions::joint_buckets); 0 = off
  ClipAugmentConfig augment;

  // Throws std::invalid_argument naming the bad field with its "data." prefix.
  void validate() const;
};
void visit_fields(ConfigVisitor& v, ClipBatchConfig& c);

// The loader options of a training run: `batch_size` items over all ranks,
// shuffled, the last partial batch of an epoch dropped, each rank's share
// when `ranks` is given.
BatchOptions training_batches(const ClipBatchConfig& data, int64_t batch_size, uint64_t seed, const Communicator* ranks);

// {"epoch", "index"}: where the loader's stream goes on.
nlohmann::json batch_position(const BatchLoader& loader);
// Moves the loader to a position batch_position wrote; InputError naming
// `state_path` when the record is damaged or the position is not in this split.
void seek_batches(BatchLoader& loader, const nlohmann::json& position, const std::string& state_path);

}  // namespace nec::train

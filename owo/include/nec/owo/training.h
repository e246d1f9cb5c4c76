// OwO pretraining runs (`nec train owo`): the JSON training config, a trainer
// that draws augmented batches from a SkeletonSet and takes AdamW steps
// (train/optimizer.h), and training checkpoints that resume.
//
//   OwoTrainingConfig config = read_owo_training_config("configs/owo_cpu.json");
//   OwoTrainer trainer(config, split_skeleton_set(all, config.hold_out()), &vectors, torch::kCPU);
//   for (int64_t step = trainer.resume("runs/owo") + 1; step <= config.steps; ++step) {   // or from 1
//     PretrainLosses l = trainer.step(step);
//     if (step % 500 == 0) trainer.save("runs/owo", step, {"runs/cache"});
//   }
//
// A training checkpoint is an OwO checkpoint (checkpoint.h; what `nec eval
// owo` and later models load) plus the training state (train/training_state.h,
// model "owo") in the same directory, replaced with it atomically; its data
// record is {"caches": [...], "train_skeletons": [hash...], "held_out_skeletons": [hash...]}.
// Steps draw their batch, augmentations and sampled pairs from (seed, step)
// alone, so a resumed run takes the same steps as one that never stopped.
#pragma once

#include "nec/owo/evaluation.h"
#include "nec/owo/pretrain.h"
#include "nec/owo/skeleton_set.h"
#include "nec/text/word_vectors.h"
#include "nec/train/loop.h"
#include "nec/train/optimizer.h"

#include <c10/core/Device.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace torch::optim {
class AdamW;
}
namespace nec::train {
class Communicator;
class ConfigVisitor;
}

namespace nec::owo {

// Which skeletons train and which are held out, and how they are augmented.
struct OwoDataConfig {
  std::vector<std::string> held_out;  // hold-out patterns (skeleton_set.h), e.g. {"spider", "snake"}
  bool cache_held_out = true;         // also hold out what the caches hold out (nec prepare --hold-out ...)
  int64_t poses_per_skeleton = 16;    // frames kept per skeleton for rest-pose augmentation
  int64_t size_buckets = 4;           // batches come from one of this many joint-count buckets (1 = any mix)
  AugmentOptions augment;

  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, OwoDataConfig& c);  // train/config_fields.h

// The encoder a training config starts from: OwoConfig's defaults with
// name_dim 100, the width of the project's GloVe vectors (text/).
inline OwoConfig default_training_encoder() {
  OwoConfig config;
  config.name_dim = 100;
  return config;
}

// Everything `nec train owo` reads from its --config file. Fields left out
// of the file keep these defaults; unknown fields are an error.
struct OwoTrainingConfig {
  OwoConfig encoder = default_training_encoder();  // saved with the model
  PretrainConfig pretrain;       // saved with the model
  train::OptimizerConfig optimizer;  // AdamW, warm-up + cosine (train/optimizer.h)
  OwoDataConfig data;
  bool names = true;             // feed joint-name embeddings; encoder.name_dim must equal the word vectors' dim
  int64_t batch_size = 16;       // skeletons per step at most, e.g. 16
  int64_t batch_joint_pairs = 0; // and at most this many B * Jmax^2 (a step's edge tensors); 0 = no limit
  int64_t steps = 2000;          // the step training ends at
  int64_t log_every = 50;        // progress line cadence off a terminal; 0 = only the last step
  int64_t validate_every = 500;  // held-out validation every N steps and at the end; 0 = never
  int64_t checkpoint_every = 500;  // checkpoint every N steps and at the end; 0 = only at the end
  uint64_t seed = 1;             // model init, batches, augmentation, sampled pairs

  void validate() const;  // throws std::invalid_argument naming the field, e.g. "optimizer.learning_rate must be ..."
  HoldOut hold_out() const { return HoldOut{data.held_out, data.cache_held_out}; }
};
// The one field list of the config file: `nec train owo --help` prints it.
void visit_fields(train::ConfigVisitor& v, OwoTrainingConfig& c);

// Parses a config file's text; `file` names it in errors. Throws nec::InputError
// "file: field 'optimizer.learning_rate' must be a number" (also for unknown fields, bad
// JSON and failed validation).
OwoTrainingConfig parse_owo_training_config(const std::string& text, const std::string& file);
// Reads and parses the config file at `path` (InputError also when it cannot be read).
OwoTrainingConfig read_owo_training_config(const std::string& path);
// Every field, as a JSON document that parse_owo_training_config reads back.
std::string owo_training_config_json(const OwoTrainingConfig& config);
// The dotted fields whose values differ, e.g. {"optimizer.learning_rate"}; the schedule
// fields (steps, log_every, validate_every, checkpoint_every) are left out:
// a resumed run may change them.
std::vector<std::string> differing_fields(const OwoTrainingConfig& a, const OwoTrainingConfig& b);

// Reads every cache (nec::read_cache) and splits their skeletons: the
// skeleton set of a run. Throws nec::InputError naming the cache when one
// cannot be read, and naming the pattern when a hold-out pattern takes no skeleton.
SkeletonSet load_skeleton_set(const std::vector<std::string>& caches, const HoldOut& hold_out,
                              int64_t poses_per_skeleton, uint64_t seed);

// The training state of an OwO training checkpoint.
struct OwoTrainingRecord {
  int64_t step = 0;
  OwoTrainingConfig config;
  nlohmann::json schedule;                      // train::LearningRateSchedule::to_json
  std::vector<std::string> data;                // the caches, as given to nec train owo
  std::vector<std::string> train_skeletons;     // content hashes
  std::vector<std::string> held_out_skeletons;  // content hashes
};

// `set` re-split by what a run trained on (`trained_hashes`, its record's
// train_skeletons), whatever the hold-out patterns say now: a held-out
// skeleton it trained on moves to train (group "train"), a training skeleton
// it never saw to held_out (group "not in its training set").
SkeletonSet split_as_trained(SkeletonSet set, const std::vector<std::string>& trained_hashes);

// <dir>/training.json, or std::nullopt when the directory has none (an OwO
// checkpoint not written by nec train owo). Throws nec::InputError for a
// damaged or foreign file.
std::optional<OwoTrainingRecord> read_owo_training_record(const std::string& dir);

class OwoTrainer {
 public:
  // `vectors` must outlive the trainer; nullptr trains without names (config.names false).
  // Throws std::invalid_argument for an empty training set or names of the wrong width.
  // `ranks`: the other processes of a data-parallel run (null: one process);
  // each step then trains on this rank's share of the batch.
  OwoTrainer(const OwoTrainingConfig& config, SkeletonSet skeletons, const text::WordVectors* vectors,
             const c10::Device& device, const train::Communicator* ranks = nullptr);
  ~OwoTrainer();
  OwoTrainer(const OwoTrainer&) = delete;
  OwoTrainer& operator=(const OwoTrainer&) = delete;

  // One optimizer step at `step` (1-based): learning rate from the schedule,
  // a batch of augmented training skeletons drawn from (seed, step). The terms
  // are the whole batch's (summed over the ranks by their shares).
  PretrainLosses step(int64_t step);
  // Scores on the held-out (or training) skeletons, un-augmented.
  std::vector<SkeletonScore> score_held_out();
  std::vector<SkeletonScore> score_train();

  // Writes a training checkpoint at `step` to `dir` (atomic, replacing one there).
  void save(const std::string& dir, int64_t step, const std::vector<std::string>& data);
  // Loads model and optimizer state from the training checkpoint `dir` and
  // returns its step. Throws nec::InputError naming the file when it is not
  // one, or when its config (differing_fields) or training skeletons differ.
  int64_t resume(const std::string& dir);

  // What `nec train owo` runs: the config's step cadence (no validation
  // without held-out skeletons), and hooks whose progress terms are "total",
  // each loss that ran, "lca_acc" and "grad"; validation on the held-out
  // skeletons "held_out_lca_acc", "offset_pct", "rebuilt", "decoded";
  // checkpoints to `out_dir` recording `data`.
  train::TrainingSchedule loop_schedule() const;
  train::TrainingHooks hooks(const std::string& out_dir, const std::vector<std::string>& data);

  OwoPretrainerImpl& model() { return *model_; }
  const SkeletonSet& skeletons() const { return skeletons_; }
  int64_t parameter_count() const;
  // "cache a,b: 70 training skeletons (11-140 joints, augmented), 20 held out (spider 10, snake 10)"
  std::string describe_data(const std::vector<std::string>& data) const;

 private:
  at::Tensor names_of(const std::vector<std::string>& canonical_names) const;
  PretrainLosses summed_over_ranks(const PretrainLosses& local, double weight) const;

  OwoTrainingConfig config_;
  SkeletonSet skeletons_;
  const text::WordVectors* vectors_;
  c10::Device device_;
  const train::Communicator* ranks_;
  train::LearningRateSchedule schedule_;
  OwoPretrainer model_{nullptr};
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  std::vector<std::vector<size_t>> buckets_;  // training skeleton indices by joint count, smallest first
};

}  // namespace nec::owo

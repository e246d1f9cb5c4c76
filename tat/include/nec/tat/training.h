// Training the tokenizer (`nec train tat`): the configuration file, and a
// trainer that draws batches from a dataset cache, takes AdamW steps
// (train/optimizer.h), validates, and writes checkpoints that resume.
//
//   TatTrainConfig config = read_tat_train_config("configs/tat_cpu.json");
//   TatTrainer trainer(config, cache, "cache/", owo, &vectors, torch::kCPU);
//   const int64_t start = resuming ? trainer.resume("runs/tat") : 0;
//   for (int64_t step = start + 1; step <= config.steps; ++step) {
//     LossTerms terms = trainer.step(step);                   // "loss", "rotation", ..., "lr"
//     if (step % 500 == 0) trainer.save("runs/tat", step);
//   }
//
// The OwO encoder is frozen (eval mode, no gradients): joint embeddings are
// computed per batch from the (possibly augmented) skeletons and their names.
// A checkpoint is a TAT checkpoint (checkpoint.h) plus the training state
// (train/training_state.h, model "tat"; data record {"epoch", "index"} of the
// batch stream). Step s draws its batch from (seed, epoch, position) and its
// random numbers from (seed, s), so a resumed run takes the steps of one that
// never stopped, on any number of ranks.
#pragma once

#include "nec/corpus/batch.h"
#include "nec/owo/pretrain.h"
#include "nec/tat/loss.h"
#include "nec/tat/metrics.h"
#include "nec/tat/tokenizer.h"
#include "nec/text/word_vectors.h"
#include "nec/train/clip_batches.h"
#include "nec/train/loop.h"
#include "nec/train/optimizer.h"

#include <nlohmann/json.hpp>
#include <torch/optim/adamw.h>

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

namespace nec::train {
class Communicator;
class ConfigVisitor;
}

namespace nec::tat {

class RememberedSkeletonEmbeddings;  // tat/inference.h

// The optimizer a TAT config starts from: peak 2e-4, warm-up 200, no weight decay, clip 1.
inline train::OptimizerConfig default_tat_optimizer() {
  train::OptimizerConfig config;
  config.learning_rate = 2e-4;
  config.final_lr_fraction = 0.1;
  config.warmup_steps = 200;
  config.weight_decay = 0.0;
  config.grad_clip = 1.0;
  return config;
}

struct TatTrainConfig {
  TatConfig model;
  LossWeights loss;
  train::OptimizerConfig optimizer = default_tat_optimizer();  // AdamW, warm-up + cosine
  train::ClipBatchConfig data;       // crop (a multiple of the downsampling), joint buckets, augmentation
  int64_t steps = 4000;              // the step training ends at
  int64_t batch_size = 32;           // clips per step over all ranks, e.g. 32
  int64_t max_joint_frames = 0;      // most B × J × T entries per forward/backward pass; a bigger batch is run
                                     // in parts whose gradients add up (less memory, same update); 0 = no limit
  int64_t log_every = 20;            // progress line cadence off a terminal; 0 = only the last step
  int64_t validate_every = 500;      // validation every N steps and at the end; 0 = never
  int64_t validation_batches = 8;    // batches of the val split per validation
  int64_t checkpoint_every = 500;    // checkpoint every N steps; 0 = only at the end
  uint64_t seed = 0;  // batches, initial weights and every step's random draws: a run repeats exactly on CPU

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
// The one field list of the config file: `nec train tat --help` prints it.
void visit_fields(train::ConfigVisitor& v, TatTrainConfig& c);

// Every field optional (defaults above); unknown fields are an error so typos
// do not pass silently. Throws nec::InputError naming the file and the field.
TatTrainConfig read_tat_train_config(const std::string& path);
TatTrainConfig tat_train_config_from_json(const nlohmann::json& object, const std::string& file);

// Loss terms of one batch ("loss", "rotation", "root", "position", "velocity",
// "vertical", "commitment", "perplexity0", ...).
using LossTerms = std::map<std::string, double>;

// Items of a batch that one forward/backward pass takes: all of them when
// max_joint_frames is 0, else as many as fit (J × T entries each), at least 1.
int64_t items_per_part(int64_t items, int64_t joint_frames_per_item, int64_t max_joint_frames);

// Forward and backward of `batch` in parts of at most `max_joint_frames`
// B × J × T entries (0: one part); the gradients add up in the tokenizer's
// parameters. Each part's loss counts by its share of the batch's items, times
// `batch_share` (a rank's share of the global batch), so the sum is the whole
// batch's loss exactly when the items have equal masks (and close to it for
// bucketed batches of similar sizes). `embeddings` is (B, J, D) or undefined
// (zero-pad kind). Returns the share-weighted terms.
LossTerms backward_in_parts(Tokenizer& tokenizer, const BatchTensors& batch, const at::Tensor& embeddings,
                            const LossWeights& weights, int64_t max_joint_frames, double batch_share = 1.0);

class TatTrainer {
 public:
  // A fresh tokenizer (initial weights and codebooks from config.seed) and
  // the frozen `owo`, on the train split of `cache` (which must outlive the
  // trainer; `data_name` describes it in checkpoints); validation on its val
  // split when it has one. `vectors` may be null when the OwO encoder reads no
  // names. `ranks`: the processes of a data-parallel run (null: one process);
  // each rank then trains on its share of every batch. Throws InputError
  // (naming data_name) when the train split makes no batch.
  TatTrainer(const TatTrainConfig& config, const DatasetCache& cache, std::string data_name, owo::OwoPretrainer owo,
             const text::WordVectors* vectors, const c10::Device& device, const train::Communicator* ranks = nullptr);
  ~TatTrainer();
  TatTrainer(const TatTrainer&) = delete;
  TatTrainer& operator=(const TatTrainer&) = delete;

  // Loads the tokenizer, optimizer, schedule and batch position of the
  // training checkpoint `dir` and returns its step. A config.steps other than
  // the checkpoint's moves the schedule's end (no jump in the rate). Throws
  // InputError naming the file when it is not a `nec train tat` checkpoint or
  // its config differs in more than steps and the log, validation and
  // checkpoint cadence.
  int64_t resume(const std::string& dir);
  // One optimizer step (1-based `step`) on the next batch; the terms are the
  // whole batch's (summed over the ranks by their shares), and "lr".
  LossTerms step(int64_t step);
  // validation_batches batches of the val split (nullopt without one), in eval mode.
  std::optional<ReconstructionMetrics> validate();
  // Writes the training checkpoint at `step` to `dir` (atomic, replacing one there).
  void save(const std::string& dir, int64_t step);

  // What `nec train tat` runs: the config's step cadence (no validation
  // without a val split), and hooks whose progress terms are "loss", the
  // reconstruction terms, "ppl<r>" per layer and "lr"; validation
  // "val_mpjpe", "val_mpjpe_no_trans", "val_geodesic_deg"; checkpoints to `out_dir`.
  train::TrainingSchedule loop_schedule() const;
  train::TrainingHooks hooks(const std::string& out_dir);

  // One step / metrics on a given batch (what step() and validate() run).
  LossTerms step_on(const Batch& batch, int64_t step);
  ReconstructionMetrics evaluate(const Batch& batch);

  Tokenizer& tokenizer() { return tokenizer_; }
  owo::OwoPretrainer& owo() { return owo_; }
  torch::optim::AdamW& optimizer() { return *optimizer_; }
  const train::LearningRateSchedule& schedule() const { return schedule_; }
  int64_t parameter_count() const;
  int train_clip_count() const { return train_->clip_count(); }
  bool has_validation() const { return validation_ != nullptr; }

 private:
  struct Inputs;
  Inputs inputs(const Batch& batch);

  TatTrainConfig config_;
  const DatasetCache& cache_;
  std::string data_name_;
  Tokenizer tokenizer_{nullptr};
  owo::OwoPretrainer owo_;
  std::unique_ptr<tat::RememberedSkeletonEmbeddings> skeleton_embeddings_;  // of the frozen owo_
  const text::WordVectors* vectors_;
  c10::Device device_;
  const train::Communicator* ranks_;
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  train::LearningRateSchedule schedule_;
  std::unique_ptr<BatchLoader> train_;
  std::unique_ptr<BatchLoader> validation_;  // null without a val split
};

}  // namespace nec::tat

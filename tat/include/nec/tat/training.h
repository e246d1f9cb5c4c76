// Training the tokenizer: the configuration file of `nec train tat` and one
// optimizer step / one validation pass on dataset batches.
//
//   TatTrainConfig config = read_tat_train_config("configs/tat_cpu.json");
//   TatTrainer trainer(Tokenizer(config.model), owo, config, &vectors);
//   for (int64_t step = 0; step < config.steps; ++step) {
//     std::map<std::string, double> terms = trainer.step(loader.next(), step);  // "loss", "rotation", ...
//   }
//
// The OwO encoder is frozen (eval mode, no gradients): joint embeddings are
// computed per batch from the (possibly augmented) skeletons and their names.
#pragma once

#include "nec/motion/batch.h"
#include "nec/owo/pretrain.h"
#include "nec/tat/loss.h"
#include "nec/tat/metrics.h"
#include "nec/tat/tokenizer.h"
#include "nec/text/word_vectors.h"

#include <nlohmann/json.hpp>
#include <torch/optim/adamw.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>

namespace nec::tat {

struct TatTrainConfig {
  TatConfig model;
  LossWeights loss;
  double learning_rate = 2e-4;       // peak, after warmup
  double final_learning_rate = 2e-5; // reached at the last step (cosine decay)
  int64_t warmup_steps = 200;
  double weight_decay = 0.0;
  double grad_clip = 1.0;            // max gradient norm; 0 = off
  int64_t steps = 4000;
  int64_t batch_size = 32;
  int64_t window_frames = 64;        // training crop T; a multiple of the downsampling
  double augment_probability = 0.5;  // rig augmentation per item
  int64_t joint_buckets = 16;        // batches of similar joint counts (BatchOptions::joint_buckets); 0 = off
  int64_t max_joint_frames = 0;      // most B × J × T entries per forward/backward pass; a bigger batch is run
                                     // in parts whose gradients add up (less memory, same update); 0 = no limit
  int64_t log_every = 20;
  int64_t validate_every = 500;
  int64_t validation_batches = 8;
  int64_t checkpoint_every = 500;
  uint64_t seed = 0;  // batches, initial weights and every step's random draws: a run repeats exactly on CPU

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

// Every field optional (defaults above); unknown fields are an error so typos
// do not pass silently. Throws nec::InputError naming the file and the field.
TatTrainConfig read_tat_train_config(const std::string& path);
nlohmann::json to_json(const TatTrainConfig& config);
TatTrainConfig tat_train_config_from_json(const nlohmann::json& object, const std::string& file);

// Learning rate at `step` (linear warmup, then cosine to final_learning_rate).
double learning_rate_at(const TatTrainConfig& config, int64_t step);

// Loss terms of one batch ("loss", "rotation", "root", "position", "velocity",
// "commitment", "perplexity0", ...).
using LossTerms = std::map<std::string, double>;

// Items of a batch that one forward/backward pass takes: all of them when
// max_joint_frames is 0, else as many as fit (J × T entries each), at least 1.
int64_t items_per_part(int64_t items, int64_t joint_frames_per_item, int64_t max_joint_frames);

// Forward and backward of `batch` in parts of at most `max_joint_frames`
// B × J × T entries (0: one part); the gradients add up in the tokenizer's
// parameters. Each part's loss counts by its share of the batch's items, so
// the sum is the whole batch's loss exactly when the items have equal masks
// (and close to it for bucketed batches of similar sizes). `embeddings` is
// (B, J, D) or undefined (zero-pad kind). Returns the share-weighted terms.
LossTerms backward_in_parts(Tokenizer& tokenizer, const BatchTensors& batch, const at::Tensor& embeddings,
                            const LossWeights& weights, int64_t max_joint_frames);

class TatTrainer {
 public:
  // `vectors` may be null when the OwO encoder reads no names. Models are moved to `device`.
  TatTrainer(Tokenizer tokenizer, owo::OwoPretrainer owo, const TatTrainConfig& config,
             const text::WordVectors* vectors, const c10::Device& device);

  // One AdamW step at the scheduled learning rate; returns the loss terms
  // ("loss", "rotation", "root", "position", "velocity", "commitment", "lr",
  // "perplexity0", ...) before the step.
  LossTerms step(const Batch& batch, int64_t step_index);
  // Metrics in eval mode without gradients; the model returns to training mode.
  ReconstructionMetrics evaluate(const Batch& batch);

  Tokenizer& tokenizer() { return tokenizer_; }
  owo::OwoPretrainer& owo() { return owo_; }
  torch::optim::AdamW& optimizer() { return *optimizer_; }

 private:
  struct Inputs;
  Inputs inputs(const Batch& batch);

  Tokenizer tokenizer_;
  owo::OwoPretrainer owo_;
  TatTrainConfig config_;
  const text::WordVectors* vectors_;
  c10::Device device_;
  std::unique_ptr<torch::optim::AdamW> optimizer_;
};

}  // namespace nec::tat

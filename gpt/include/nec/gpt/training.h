// Training the GPT (`nec train gpt`): teacher forcing on the token codes of
// the captioned train clips (open_token_set), every caption level, with
// token corruption (T2M-GPT's pkeep) and caption dropout (for
// classifier-free guidance), on the train/ library.
//
//   GptTrainConfig config = read_gpt_train_config("configs/gpt_cpu.json");
//   GptTrainer trainer(config, cache, "cache/", tokenizer_session, "runs/tat", "spm.model", &vectors, torch::kCPU);
//   run_training(trainer.loop_schedule(), 0, "runs/gpt", trainer.hooks("runs/gpt"), progress);
//
// A step's batch is drawn from (seed, step) alone: each item a clip, one of
// its captions and a crop of at most max_steps - 1 steps (the end code is
// the target after the crop's last step when the crop reaches the clip's
// end, else the next step). So a resumed run takes the steps of one that
// never stopped, and on several ranks each takes its share of the same batch.
// Loss: cross-entropy of every layer's code of every predicted step (and the
// end), averaged per item, then over the batch.
// Validation: the same loss and the accuracy of layer 0 on the val clips
// (their first caption, the first max_steps - 1 steps), no corruption or dropout.
#pragma once

#include "nec/gpt/model.h"
#include "nec/gpt/token_set.h"
#include "nec/corpus/dataset.h"
#include "nec/tat/session.h"
#include "nec/train/loop.h"
#include "nec/train/optimizer.h"

#include <torch/optim/adamw.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace nec::train {
class Communicator;
class ConfigVisitor;
}

namespace nec::gpt {

// The optimizer a GPT config starts from: peak 3e-4, warm-up 100, weight decay 0.01, clip 1.
inline train::OptimizerConfig default_gpt_optimizer() {
  train::OptimizerConfig config;
  config.learning_rate = 3e-4;
  config.final_lr_fraction = 0.05;
  config.warmup_steps = 100;
  config.weight_decay = 0.01;
  config.grad_clip = 1.0;
  return config;
}

struct GptTrainConfig {
  GptConfig model;
  train::OptimizerConfig optimizer = default_gpt_optimizer();
  double token_keep = 0.8;       // chance an input step keeps its codes; else random codes (T2M-GPT's pkeep)
  double caption_dropout = 0.1;  // chance an item's caption is dropped (classifier-free guidance)
  int64_t steps = 3000;          // the step training ends at
  int64_t batch_size = 32;       // items per step over all ranks
  int64_t log_every = 20;        // progress line cadence off a terminal; 0 = only the last step
  int64_t validate_every = 250;  // validation every N steps and at the end; 0 = never
  int64_t checkpoint_every = 500;  // checkpoint every N steps; 0 = only at the end
  uint64_t seed = 0;             // initial weights, batches and every step's random draws

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, GptTrainConfig& c);

// Every field optional; unknown fields are an error. InputError naming the file and the field.
GptTrainConfig read_gpt_train_config(const std::string& path);

// One teacher-forced batch.
struct GptBatch {
  std::vector<std::string> captions;  // (B)
  at::Tensor skeleton_features;       // (B, F)
  at::Tensor inputs;                  // (B, S, R) int64, 0 at padding
  at::Tensor targets;                 // (B, S + 1, R) int64: codes; layer 0 = K at the end; -1 where not scored
  at::Tensor drop_text;               // (B) bool
};

// Per-item mean cross-entropy of every scored target, summed over items and
// divided by `global_items`; the layer-0 accuracy over the scored steps.
struct GptLoss {
  at::Tensor loss;           // ()
  double first_accuracy = 0;  // share of scored steps whose most likely layer-0 code is the target
};
GptLoss gpt_loss(const GptLogits& logits, const at::Tensor& targets, int64_t global_items);

// The loss of a batch whose captions the text backbone has read (`captions`;
// batch.captions is not read): the condition, then in training mode
// T2M-GPT's corruption (each input step keeps its codes with chance
// token_keep, else gets random ones, drawn from torch's generator), the
// teacher-forced forward and gpt_loss. What GptTrainer's steps and validation
// compute, and the synthetic step of the benchmark (gpt/synthetic.h).
GptLoss teacher_forced_loss(TokenGptImpl& model, const text::TextBatch& captions, const GptBatch& batch,
                            double token_keep, int64_t global_items, const c10::Device& device);

class GptTrainer {
 public:
  // A fresh GPT (weights from config.seed; with the pieces backbone, piece
  // embeddings from the word vectors where a piece is a whole word) to predict
  // the codes of `tokenizer` (a session opened on `tokenizer_dir`), on the
  // captioned clips of `cache`, read by `captions` (saved with checkpoints). `vectors`: the word vectors of the text encoder (null when
  // model.text.word_dim is 0). InputError when the train split has no
  // captioned clip, or a caption is longer than model.text.max_pieces.
  GptTrainer(const GptTrainConfig& config, const DatasetCache& cache, std::string data_name,
             tat::TokenizerSession& tokenizer, const std::string& tokenizer_dir, text::CaptionReader captions,
             const text::WordVectors* vectors, const c10::Device& device, const train::Communicator* ranks = nullptr);
  ~GptTrainer();
  GptTrainer(const GptTrainer&) = delete;
  GptTrainer& operator=(const GptTrainer&) = delete;

  // Loads the model, optimizer and schedule of the training checkpoint `dir`; returns its step.
  int64_t resume(const std::string& dir);
  // One optimizer step (1-based): {"loss", "accuracy", "lr"}.
  train::LossTerms step(int64_t step);
  // {"val_loss", "val_accuracy"} on the val clips (nullopt without any).
  std::optional<train::LossTerms> validate();
  void save(const std::string& dir, int64_t step);

  train::TrainingSchedule loop_schedule() const;
  train::TrainingHooks hooks(const std::string& out_dir);

  TokenGpt& model() { return model_; }
  int64_t parameter_count() const;
  int train_clip_count() const { return static_cast<int>(train_rows_.size()); }
  bool has_validation() const { return !validation_rows_.empty(); }
  // The batch of `step` (all ranks' items when `whole`, else this rank's share).
  GptBatch batch(int64_t step, bool whole = false) const;

 private:
  // Items of token-set rows with the given captions and crops [start, start + steps).
  GptBatch make_batch(const std::vector<int>& rows, const std::vector<std::string>& captions,
                      const std::vector<int>& starts, const std::vector<int>& lengths,
                      const std::vector<bool>& drop_text) const;
  GptLoss loss_of(const GptBatch& batch, int64_t global_items);

  GptTrainConfig config_;
  const DatasetCache& cache_;
  std::string data_name_;
  tat::TokenizerSession& tokenizer_;
  text::CaptionReader captions_;
  const text::WordVectors* vectors_;
  c10::Device device_;
  const train::Communicator* ranks_;
  TokenSet tokens_;
  at::Tensor skeleton_features_;  // (skeletons of the cache, F) on the CPU
  std::vector<int> train_rows_, validation_rows_;  // token-set rows
  TokenGpt model_{nullptr};
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  train::LearningRateSchedule schedule_;
};

}  // namespace nec::gpt

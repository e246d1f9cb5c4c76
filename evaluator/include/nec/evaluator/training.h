// Training the evaluator (`nec train evaluator`): motion and text encoders
// trained contrastively on (clip, caption) pairs of a dataset cache, with the
// frozen OwO encoder's joint embeddings and rig augmentation on the fly (the
// embedding must describe the motion, not the rig).
//
//   EvaluatorTrainConfig config = read_evaluator_train_config("configs/evaluator_cpu.json");
//   const text::CaptionReader captions = text::CaptionReader::for_training(config.model.text, pieces_path);
//   EvaluatorTrainer trainer(config, cache, "cache/", owo, captions, &vectors, torch::kCPU);
//   run_training(trainer.loop_schedule(), 0, trainer.hooks("runs/eval"));
//
// Loss: symmetric InfoNCE over the batch (CLIP) with a learnt temperature;
// items whose normalized captions are equal count as positives of each other
// (the zoo repeats its short captions across creatures), so they are not
// pushed apart. Each item draws one of its clip's captions (every level).
// Batches of similar joint counts (data.joint_buckets, off by default) put
// clips of one body plan together: harder negatives (the same creature doing
// something else), but such a batch never contrasts one plan with another.
// Validation: R-Precision (batches of 32, 20 repeats) of the val clips with
// their first caption; the best R@3 is kept in <out>/best.
// Data-parallel: each rank contrasts its share of the batch (the negatives
// are the share's items) and the gradients are averaged.
#pragma once

#include "nec/evaluator/evaluator.h"
#include "nec/corpus/batch.h"
#include "nec/train/clip_batches.h"
#include "nec/train/loop.h"
#include "nec/train/optimizer.h"
#include "nec/text/synonyms.h"

#include <nlohmann/json.hpp>
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
namespace nec::tat {
class RememberedSkeletonEmbeddings;
}

namespace nec::evaluator {

// The optimizer an evaluator config starts from: peak 3e-4, warm-up 100, weight decay 0.01, clip 1.
inline train::OptimizerConfig default_evaluator_optimizer() {
  train::OptimizerConfig config;
  config.learning_rate = 3e-4;
  config.final_lr_fraction = 0.05;
  config.warmup_steps = 100;
  config.weight_decay = 0.01;
  config.grad_clip = 1.0;
  return config;
}

// The batches an evaluator config starts from: 64-frame crops, no joint buckets (see above).
inline train::ClipBatchConfig default_evaluator_batches() {
  train::ClipBatchConfig data;
  data.joint_buckets = 0;
  return data;
}

}  // namespace nec::evaluator
namespace nec::text {
void visit_fields(train::ConfigVisitor& v, SynonymOptions& c);  // "per_word", "min_cosine"
}  // namespace nec::text
namespace nec::evaluator {

// Caption augmentation (text/synonyms.h): in training, each caption word that
// has synonyms among the word vectors is replaced by one with this chance, so
// that the text encoder reads words no caption used ("strolls" for "walks").
struct CaptionAugmentConfig {
  double synonym_probability = 0.0;  // per word, e.g. 0.25; 0 = off
  text::SynonymOptions synonyms;     // which neighbours count as synonyms
  // The frozen sentence encoder as a teacher of the caption space (backbone "use-lite"): weight of
  // caption_teacher_loss beside the contrastive loss (0 = off), and its temperature.
  double teacher_weight = 0.0;
  double teacher_temperature = 0.05;
};
void visit_fields(train::ConfigVisitor& v, CaptionAugmentConfig& c);

struct EvaluatorTrainConfig {
  EvaluatorConfig model;
  train::OptimizerConfig optimizer = default_evaluator_optimizer();  // AdamW, warm-up + cosine
  train::ClipBatchConfig data = default_evaluator_batches();  // crop, joint buckets, rig augmentation
  CaptionAugmentConfig captions;  // synonym rewrites of the train captions
  int64_t steps = 3000;          // the step training ends at
  int64_t batch_size = 64;       // (clip, caption) pairs per step over all ranks
  int64_t log_every = 20;        // progress line cadence off a terminal; 0 = only the last step
  int64_t validate_every = 250;  // validation every N steps and at the end; 0 = never
  int64_t checkpoint_every = 500;  // checkpoint every N steps; 0 = only at the end
  uint64_t seed = 0;             // batches, initial weights and every step's random draws

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, EvaluatorTrainConfig& c);

// Every field optional; unknown fields are an error. InputError naming the file and the field.
EvaluatorTrainConfig read_evaluator_train_config(const std::string& path);

// Symmetric InfoNCE of matched rows: motion (B, D) and text (B, D) unit
// length, scale () the logit scale, same (B, B) bool: true where items i and j
// count as a match (the diagonal, and equal captions). The target of row i is
// spread evenly over its matches. -> ()
at::Tensor contrastive_loss(const at::Tensor& motion, const at::Tensor& text, const at::Tensor& scale,
                            const at::Tensor& same);

// How far the text head's caption-to-caption similarities within a batch are from the frozen sentence
// encoder's: text (B, D) and teacher (B, T) unit rows; each row's similarities to the other captions, divided
// by `temperature`, as distributions (softmax over j != i), KL(teacher || head) averaged over the rows. So
// that words the captions never used land where the encoder puts them. -> ()
at::Tensor caption_teacher_loss(const at::Tensor& text, const at::Tensor& teacher, double temperature);

// What one contrastive step reads: EvaluatorTrainer::step makes it from its
// batch (the OwO embeddings of its skeletons, its captions read), synthetic.h
// from torch's generator.
struct ContrastiveBatch {
  at::Tensor features;          // (B, T, J, 9) Θ as batches hold it, zero outside the masks
  at::Tensor joint_mask;        // (B, J) bool
  at::Tensor frame_mask;        // (B, T) bool
  at::Tensor joint_embeddings;  // (B, J, E) of the frozen OwO encoder
  text::TextBatch captions;     // one caption per item, as the text encoder reads it
  at::Tensor same;              // (B, B) bool: the matches of contrastive_loss
};

// The training loss of `model` (in the mode it is in) on `batch`: the motions
// embedded, then the captions (the order of their dropout draws), and
// contrastive_loss at the model's logit scale; plus teacher_weight x
// caption_teacher_loss against the batch's encoder sentence vectors when
// teacher_weight > 0. -> ()
at::Tensor contrastive_batch_loss(EvaluatorImpl& model, const ContrastiveBatch& batch, double teacher_weight = 0.0,
                                  double teacher_temperature = 0.05);

class EvaluatorTrainer {
 public:
  // A fresh evaluator (weights from config.seed; with the pieces backbone,
  // piece embeddings from the word vectors where a piece is a whole word) and
  // the frozen `owo`, on the train-split clips of `cache` that have captions.
  // `captions` reads them (CaptionReader::for_training of config.model.text)
  // and goes into checkpoints. `vectors` may be null when neither encoder reads words. InputError when
  // the train split has fewer captioned clips than a batch, or a train or val
  // caption is longer than model.text.max_pieces.
  EvaluatorTrainer(const EvaluatorTrainConfig& config, const DatasetCache& cache, std::string data_name,
                   owo::OwoPretrainer owo, text::CaptionReader captions, const text::WordVectors* vectors,
                   const c10::Device& device, const train::Communicator* ranks = nullptr);
  ~EvaluatorTrainer();
  EvaluatorTrainer(const EvaluatorTrainer&) = delete;
  EvaluatorTrainer& operator=(const EvaluatorTrainer&) = delete;

  // Loads the model, optimizer, schedule, batch position and best validation
  // of the training checkpoint `dir`; returns its step (as TatTrainer::resume).
  int64_t resume(const std::string& dir);
  // One optimizer step (1-based) on the next batch: {"loss", "scale", "lr"}.
  train::LossTerms step(int64_t step);
  // R-Precision of the val clips (nullopt without a val split): {"val_r1", "val_r2", "val_r3", "val_mm_dist"}.
  std::optional<train::LossTerms> validate();
  // The training checkpoint at `step` in `dir` (atomic), with best/ (the
  // newer best model, else the one there) inside.
  void save(const std::string& dir, int64_t step);

  train::TrainingSchedule loop_schedule() const;
  // Progress "loss", "scale", "lr"; validation as validate(), and when R@3
  // beats the best so far, <out_dir>/best is written; checkpoints to out_dir.
  train::TrainingHooks hooks(const std::string& out_dir);

  Evaluator& model() { return model_; }
  int64_t parameter_count() const;
  int train_clip_count() const { return train_->clip_count(); }
  bool has_validation() const { return !validation_clips_.empty(); }
  const text::SynonymTable& synonyms() const { return synonyms_; }
  int64_t best_step() const { return info_.best_step; }
  double best_r_precision() const { return info_.best_r_precision; }

 private:
  EvaluatorCheckpointInfo info(int64_t step) const;
  // The batch's captions with synonyms drawn for `step` (config.captions); the same captions when off.
  std::vector<std::string> rewritten_captions(const std::vector<std::string>& captions, int64_t step) const;

  EvaluatorTrainConfig config_;
  const DatasetCache& cache_;
  std::string data_name_;
  Evaluator model_{nullptr};
  owo::OwoPretrainer owo_;
  std::unique_ptr<tat::RememberedSkeletonEmbeddings> skeleton_embeddings_;  // of the frozen owo_
  text::CaptionReader captions_;  // written into every checkpoint
  const text::WordVectors* vectors_;
  c10::Device device_;
  const train::Communicator* ranks_;
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  train::LearningRateSchedule schedule_;
  std::unique_ptr<BatchLoader> train_;
  std::vector<int> validation_clips_;
  text::SynonymTable synonyms_;  // of the train captions' words; empty when captions.synonym_probability is 0
  EvaluatorCheckpointInfo info_;  // best_step, best_r_precision
  Evaluator best_model_{nullptr};  // a copy of the model at its best validation
  bool best_pending_ = false;      // best_model_ is newer than <out>/best
};

// Fewer captioned val clips than this: no validation (and no best model).
constexpr size_t kMinValidationClips = 4;

// The train-split (or other split) clips of `cache` that have at least one caption.
std::vector<int> captioned_clips(const DatasetCache& cache, Split split);

}  // namespace nec::evaluator

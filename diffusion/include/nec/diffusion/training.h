// Training the diffusion model (`nec train diffusion --stage pose|motion`),
// in two stages as How to Move Your Dragon does (section 5.4, appendix B.1):
//
//   stage pose:   a fresh denoiser, spatial blocks only, on single frames
//                 (pose_frames frames drawn from each item's crop, each a pose
//                 of its own with its root velocity); the caption encoder
//                 trains with it.
//   stage motion: the pose model's weights frozen (or trained too:
//                 train_pose_model); the temporal blocks and the frame
//                 encoding trained on crops of data.window_frames.
//
//   DiffusionTrainConfig config = read_diffusion_train_config("configs/diffusion_pose_cpu.json");
//   DiffusionTrainer trainer(config, DiffusionStage::kPose, cache, "cache/", owo, std::nullopt, "spm.model",
//                            &vectors, torch::kCPU);
//   run_training(trainer.loop_schedule(), 0, trainer.hooks("runs/diffusion-pose"));
//
// Each item: a crop of a train clip (rig augmentation on the fly, every
// caption level; a clip without a caption trains the unconditioned model),
// in standardized model space; a timestep t uniform in [0, noise_steps);
// x_t = add_noise(x0, ε). Loss: mean squared error of the predicted x0 over
// the item's real frames, joints and the channels each joint uses, averaged
// per item, then over the batch. Caption dropout (for classifier-free
// guidance) replaces an item's caption by the learnt null caption.
// Validation: the same loss on the val clips (no augmentation or dropout),
// at fixed timesteps and noise, so that it is comparable between checkpoints;
// and how much of the joints' turning (pose and speed) whole samples of val
// clips keep (sampled_turning), which the loss hardly sees.
#pragma once

#include "nec/diffusion/checkpoint.h"
#include "nec/diffusion/noise_schedule.h"
#include "nec/text/word_vectors.h"
#include "nec/corpus/batch.h"
#include "nec/train/clip_batches.h"
#include "nec/train/loop.h"
#include "nec/train/optimizer.h"

#include <torch/optim/adamw.h>

#include <cstdint>
#include <functional>
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
struct BatchTensors;
}

namespace nec::diffusion {

// The optimizer a diffusion config starts from: peak 2e-4, warm-up 100, weight decay 0, clip 1.
inline train::OptimizerConfig default_diffusion_optimizer() {
  train::OptimizerConfig config;
  config.learning_rate = 2e-4;
  config.final_lr_fraction = 0.1;
  config.warmup_steps = 100;
  config.weight_decay = 0.0;
  config.grad_clip = 1.0;
  return config;
}

struct DiffusionTrainConfig {
  DenoiserConfig model;            // the pose stage's; the motion stage takes the pose model's
  train::OptimizerConfig optimizer = default_diffusion_optimizer();
  train::ClipBatchConfig data;     // crops, joint buckets, rig augmentation
  int64_t pose_frames = 8;         // pose stage: frames drawn from each item's crop
  double caption_dropout = 0.1;    // chance an item's caption is dropped (classifier-free guidance)
  double velocity_weight = 0.0;    // motion stage: weight of velocity_loss beside the x0 loss
  bool train_pose_model = false;   // motion stage: the pose model trains too (the paper freezes it)
  int64_t steps = 3000;            // the step training ends at
  int64_t batch_size = 32;         // items per step over all ranks
  int64_t log_every = 20;          // progress line cadence off a terminal; 0 = only the last step
  int64_t validate_every = 250;    // validation every N steps and at the end; 0 = never
  int64_t checkpoint_every = 500;  // checkpoint every N steps; 0 = only at the end
  uint64_t seed = 0;               // initial weights, batches and every step's random draws

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, DiffusionTrainConfig& c);

// Every field optional; unknown fields are an error. InputError naming the file and the field.
DiffusionTrainConfig read_diffusion_train_config(const std::string& path);

// Masked mean squared error: predicted and target (B, T, J, C), used (B, T, J, C) bool; per item, then summed
// over items and divided by global_items. -> ()
at::Tensor denoising_loss(const at::Tensor& predicted, const at::Tensor& target, const at::Tensor& used,
                          int64_t global_items);

// The same over frame-to-frame differences (a frame and the one before, both used): what the x0 loss of
// each frame alone does not see, the jitter between frames whose errors are independent. -> ()
at::Tensor velocity_loss(const at::Tensor& predicted, const at::Tensor& target, const at::Tensor& used,
                         int64_t global_items);

// A batch's captions read for the text encoder, and the items (B) bool that read the null caption instead.
struct DenoisingCaptions {
  text::TextBatch text;
  at::Tensor dropped;
};

// What a stage trains with besides its data: the frozen OwO encoder, the
// piece model, the pose model (motion stage) and the word vectors the caption
// and OwO encoders read (none when neither reads words).
struct DiffusionTrainingInputs {
  owo::OwoPretrainer owo{nullptr};
  text::CaptionReader captions;
  std::optional<LoadedDiffusion> pose;
  std::optional<text::WordVectors> vectors;
};

// The inputs from the checkpoint being resumed (`resume_dir` not empty), else
// the pose stage's `owo_dir` and `pieces_path` (the piece model when
// model.text reads pieces) or the motion stage's `pose_dir` (a pose-stage checkpoint). Sets config.model's fields that come
// from them: the pose model's whole config when a pose stage resumes, else the
// skeleton width and vocabulary of a fresh one. InputError naming the file for
// a damaged checkpoint, a motion-stage `pose_dir`, or word vectors whose width
// differs from the OwO encoder's names.
DiffusionTrainingInputs load_training_inputs(DiffusionStage stage, DiffusionTrainConfig& config,
                                             const std::string& resume_dir, const std::string& owo_dir,
                                             const std::string& pieces_path, const std::string& pose_dir,
                                             const std::string& glove_path);

class DiffusionTrainer {
 public:
  // Stage pose: a fresh denoiser (weights from config.seed; with the pieces
  // backbone, piece embeddings from the word vectors where a piece is a whole
  // word; data statistics from
  // the train clips) with the frozen `owo`. Stage motion: the denoiser of
  // `pose` (a pose-stage checkpoint, or the motion-stage one being resumed)
  // with its pose model's weights frozen. `vectors`: the word vectors the text and OwO encoders
  // read (null when neither does). InputError when the train split is
  // smaller than a batch or a caption is longer than the text encoder takes.
  DiffusionTrainer(const DiffusionTrainConfig& config, DiffusionStage stage, const DatasetCache& cache,
                   std::string data_name, owo::OwoPretrainer owo, std::optional<LoadedDiffusion> pose,
                   text::CaptionReader captions, const text::WordVectors* vectors, const c10::Device& device,
                   const train::Communicator* ranks = nullptr);
  ~DiffusionTrainer();
  DiffusionTrainer(const DiffusionTrainer&) = delete;
  DiffusionTrainer& operator=(const DiffusionTrainer&) = delete;

  // Loads the model, optimizer, schedule and batch position of the training checkpoint `dir`; returns its step.
  int64_t resume(const std::string& dir);
  // One optimizer step (1-based) on the next batch: {"loss", "lr"}.
  train::LossTerms step(int64_t step);
  // {"val_loss", "val_sampled_pose_kept", "val_sampled_speed_kept"} on the val clips (nullopt without any).
  std::optional<train::LossTerms> validate();
  void save(const std::string& dir, int64_t step);

  train::TrainingSchedule loop_schedule() const;
  train::TrainingHooks hooks(const std::string& out_dir);

  MotionDenoiser& model() { return model_; }
  DiffusionStage stage() const { return stage_; }
  int64_t trained_parameter_count() const;
  int train_clip_count() const { return train_->clip_count(); }
  bool has_validation() const { return validation_ != nullptr; }

 private:
  // The loss of a batch, each item's draws from draw_seed and its place in the whole batch;
  // `validation`: no caption dropout.
  at::Tensor loss_of(const Batch& batch, bool validation, uint64_t draw_seed);
  // The batch's skeletons (x: its tensors on the device) with their frozen OwO embeddings.
  SkeletonInputs skeleton_inputs(const Batch& batch, const tat::BatchTensors& x);
  // The batch's captions read; item i reads the null caption when it has none or drop(i).
  DenoisingCaptions read_captions(const Batch& batch, const std::function<bool(int64_t)>& drop);
  std::vector<at::Tensor> trained_parameters();
  void train_mode();

  DiffusionTrainConfig config_;
  DiffusionStage stage_;
  const DatasetCache& cache_;
  std::string data_name_;
  owo::OwoPretrainer owo_;
  std::unique_ptr<tat::RememberedSkeletonEmbeddings> skeleton_embeddings_;  // of the frozen owo_
  text::CaptionReader captions_;  // read the captions; saved with checkpoints
  const text::WordVectors* vectors_;
  c10::Device device_;
  const train::Communicator* ranks_;
  NoiseSchedule schedule_;
  MotionDenoiser model_{nullptr};
  std::unique_ptr<BatchLoader> train_, validation_;
  std::unique_ptr<BatchLoader> sampled_clips_;  // one val clip a batch, spread over the split: sampled whole
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  train::LearningRateSchedule lr_schedule_;
};

}  // namespace nec::diffusion

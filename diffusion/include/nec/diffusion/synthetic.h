// Synthetic diffusion training inputs and the bare training step that the
// benchmark and the golden test compare with the Python peer
// (benchmarks/peer_diffusion_step.py draws the same numbers in the same order
// from the same torch generator). No dataset, OwO encoder or sentence encoder
// is read: random joint embeddings stand in for OwO's and a random use-lite
// TextBatch for the sentence encoder's reading of the captions.
//
//   DiffusionTrainConfig config = synthetic_stage_config(configs_dir, DiffusionStage::kMotion);
//   torch::manual_seed(0);
//   SyntheticDiffusionBatch x = synthetic_diffusion_batch(config, DiffusionStage::kMotion, /*joints=*/22);
//   MotionDenoiser model = synthetic_denoiser(config, DiffusionStage::kMotion, x);
//   auto adamw = train::make_adamw(trained_parameters(*model, DiffusionStage::kMotion, config.train_pose_model), config.optimizer);
//   const double loss = synthetic_diffusion_train_step(*model, *adamw, x, config, DiffusionStage::kMotion, 1);
#pragma once

#include "nec/diffusion/checkpoint.h"
#include "nec/diffusion/denoiser.h"
#include "nec/diffusion/objective.h"
#include "nec/diffusion/training.h"

#include <cstdint>
#include <string>
#include <vector>

namespace torch::optim {
class Optimizer;
}

namespace nec::diffusion {

// DIR/diffusion_pose_cpu.json, or for the motion stage DIR/diffusion_motion_cpu.json with the pose config's model
// (as the motion stage takes the pose model's); skeleton_dim = encoder.dim of DIR/owo_cpu.json, as
// `nec train diffusion` sets it from the OwO checkpoint.
DiffusionTrainConfig synthetic_stage_config(const std::string& configs_dir, DiffusionStage stage);

struct SyntheticDiffusionBatch {
  DenoisingBatch batch;            // B = batch_size items, as DiffusionTrainer::loss_of draws them
  std::vector<at::Tensor> clips;   // each item's model space over its real frames and joints (T_i, J_i, C)
};

// From torch's global generator, in this order: Θ (random_features) of B x
// window_frames x `joints`; random trees and rest offsets; each item's joint
// count (item 0 `joints`, the others down to 3/4 of it, as one joint bucket
// holds) and frame count (item 0 the whole window, the others down to half
// of it), Θ zero past them as a batch pads; joint embeddings (B, J, E) zero at
// padding; captions: a piece count in [1, kSyntheticPieces] per item, use-lite
// features (B, P, 512) zero at padding and a unit sentence vector per item;
// the pose stage's pose_frames frames per item; timesteps; noise of each
// item's own joints; caption dropout.
SyntheticDiffusionBatch synthetic_diffusion_batch(const DiffusionTrainConfig& config, DiffusionStage stage,
                                                  int64_t joints);

// A fresh denoiser (torch's global generator) with data statistics from the
// batch's clips. The motion stage's pose model is frozen and, standing in for
// trained pose weights (its zero-initialised gates and output would leave the
// temporal blocks no gradient), gets N(0, kPoseStandInStd²) added to every
// pose parameter, in named_parameters() order.
MotionDenoiser synthetic_denoiser(const DiffusionTrainConfig& config, DiffusionStage stage,
                                  const SyntheticDiffusionBatch& inputs);
constexpr double kPoseStandInStd = 0.05;
constexpr int64_t kSyntheticPieces = 12;  // the longest synthetic caption, in pieces

// DiffusionTrainer::step after its batch is drawn: train mode, zero_grad,
// denoising_objective, backward, train::optimizer_step at the schedule's rate
// of `step` (1-based) over the stage's trained parameters. Returns the loss
// before the step.
double synthetic_diffusion_train_step(MotionDenoiserImpl& model, torch::optim::Optimizer& optimizer,
                                      const SyntheticDiffusionBatch& inputs, const DiffusionTrainConfig& config,
                                      DiffusionStage stage, int64_t step);

}  // namespace nec::diffusion

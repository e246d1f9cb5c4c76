// Diffusion checkpoints: the denoiser with everything generation needs, so
// one directory is all `nec generate --model DIR` reads.
//
//   <dir>/config.json   {"format": "nec-diffusion", "version": 1, "architecture": "MotionDenoiser",
//                        "denoiser": DenoiserConfig, "stage": "pose" | "motion", "fps": 30,
//                        "training_step": 3000, "data": "cache/ (1,400 train clips)",
//                        "tensors": "tensors.pt", "pieces": "pieces.model", "owo": "owo"}
//   <dir>/tensors.pt    the denoiser's parameters and data statistics (its text encoder included)
//   <dir>/pieces.model  the caption piece model its text encoder reads (backbone "pieces" only)
//   <dir>/owo/          the frozen OwO checkpoint whose joint embeddings it reads
//   <dir>/training.json, optimizer.pt   optional: the training state for --resume
//
//   save_diffusion_checkpoint("runs/diffusion", *model, *owo, captions, info);
//   LoadedDiffusion d = load_diffusion_checkpoint("runs/diffusion");   // CPU, eval mode
#pragma once

#include "nec/diffusion/denoiser.h"
#include "nec/owo/pretrain.h"
#include "nec/text/text_encoder.h"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

namespace nec::diffusion {

constexpr const char* kDiffusionCheckpointFormat = "nec-diffusion";
constexpr int kDiffusionCheckpointVersion = 1;

// Stage one: the pose model (spatial blocks, single frames); stage two: the motion model (temporal blocks added).
enum class DiffusionStage { kPose, kMotion };
const char* to_string(DiffusionStage stage);  // "pose", "motion"

struct DiffusionCheckpointInfo {
  DiffusionStage stage = DiffusionStage::kPose;
  double fps = 30.0;          // the corpus fps it was trained at
  int64_t training_step = 0;  // steps of this stage
  std::string data;           // what it was trained on
};

// Writes `dir` atomically: config, tensors, what the captions need
// (text::save_checkpoint_captions) and the OwO checkpoint; `extra` may add
// files to the temporary directory first.
void save_diffusion_checkpoint(const std::string& dir, MotionDenoiserImpl& model, owo::OwoPretrainerImpl& owo,
                               const text::CaptionReader& captions, const DiffusionCheckpointInfo& info,
                               const std::function<void(const std::string&)>& extra = {});

struct LoadedDiffusion {
  MotionDenoiser model{nullptr};  // CPU, eval mode
  owo::OwoPretrainer owo{nullptr};  // CPU, eval mode
  text::CaptionReader captions;
  DiffusionCheckpointInfo info;
};

// InputError naming the file for a missing or damaged checkpoint, one of
// another kind (e.g. a GPT given for a diffusion model) or version, with a hint.
LoadedDiffusion load_diffusion_checkpoint(const std::string& dir);

}  // namespace nec::diffusion

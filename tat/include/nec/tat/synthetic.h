// Synthetic tokenizer inputs and the bare training step that the benchmarks
// and the golden test compare with the Python peer (benchmarks/peer_tat_step.py
// draws the same numbers in the same order from the same torch generator).
//
//   torch::manual_seed(0);
//   SyntheticBatch x = synthetic_batch(16, 64, 22, 64);
//   Tokenizer model(config.model);
//   auto adamw = train::make_adamw(model->parameters(), config.optimizer);
//   const double loss = synthetic_train_step(*model, *adamw, x, config, /*step=*/1);  // the loss before the step
#pragma once

#include "nec/tat/batch_tensors.h"
#include "nec/tat/tokenizer.h"
#include "nec/tat/training.h"

#include <cstdint>

namespace torch::optim {
class Optimizer;
}

namespace nec::tat {

// (..., 6) Gaussian -> valid rot6D of Haar-random rotations (Gram-Schmidt).
at::Tensor random_rot6d(at::IntArrayRef leading);
// Θ (B, T, J, 9): root displacement ~ N(0, 0.02²) per frame, frame 0 at height
// 0.9; other joints' translation channels zero; random rotations everywhere.
at::Tensor random_features(int64_t batch, int64_t frames, int64_t joints);

struct SyntheticBatch {
  BatchTensors batch;     // all joints and frames real; random trees (parents before children), offsets ~ N(0, 0.1²)
  at::Tensor embeddings;  // (B, J, E) fixed, in place of OwO's
};
SyntheticBatch synthetic_batch(int64_t batch, int64_t frames, int64_t joints, int64_t embedding_dim);

// TatTrainer::step_on without the batch conversion and the OwO embeddings:
// forward, loss, backward, train::optimizer_step at the schedule's rate of
// `step` (1-based), the codebooks' update. Returns the loss before the step.
double synthetic_train_step(TokenizerImpl& model, torch::optim::Optimizer& optimizer, const SyntheticBatch& inputs,
                            const TatTrainConfig& config, int64_t step);

}  // namespace nec::tat

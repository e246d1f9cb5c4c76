// Synthetic evaluator inputs and the bare training step that the benchmark
// and the golden test compare with the Python peer
// (benchmarks/peer_evaluator_step.py draws the same numbers in the same order
// from the same torch generator).
//
//   torch::manual_seed(0);
//   const ContrastiveBatch x = synthetic_contrastive_batch(64, 64, 22, 64);
//   Evaluator model(config.model);
//   auto adamw = train::make_adamw(model->parameters(), config.optimizer);
//   const double loss = synthetic_evaluator_train_step(*model, *adamw, x, config, /*step=*/1);  // before the step
#pragma once

#include "nec/evaluator/evaluator.h"
#include "nec/evaluator/training.h"

#include <cstdint>

namespace torch::optim {
class Optimizer;
}

namespace nec::evaluator {

// Captions of the synthetic batch: kSyntheticMinPieces to kSyntheticPieces pieces each.
constexpr int64_t kSyntheticPieces = 12;
constexpr int64_t kSyntheticMinPieces = 4;

// B items of T frames on skeletons of at most J joints, as a batch of a joint
// bucket holds them: item 0 has J joints, the others J - J / 4 to J, and
// T / 2 to T real frames; Θ random (tat::random_features), zero outside the
// masks; joint embeddings (B, J, E) ~ N(0, 1) in place of OwO's, zero at
// padded joints. Captions as the use-lite backbone gives them: per-piece
// features ~ N(0, 1) (zero at padding; read only by a text encoder with
// layers or piece_memory) and unit sentence vectors; caption ids
// uniform in [0, 4 B), so a few items share a caption and match each other.
ContrastiveBatch synthetic_contrastive_batch(int64_t batch, int64_t frames, int64_t joints, int64_t embedding_dim);

// EvaluatorTrainer::step after its batch is made: train mode, zero_grad, the
// contrastive loss, backward, train::optimizer_step at the schedule's rate of
// `step` (1-based). Returns the loss before the step.
double synthetic_evaluator_train_step(EvaluatorImpl& model, torch::optim::Optimizer& optimizer,
                                      const ContrastiveBatch& inputs, const EvaluatorTrainConfig& config, int64_t step);

}  // namespace nec::evaluator

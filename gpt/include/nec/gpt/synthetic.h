// A synthetic GPT batch and the bare training step that the benchmark and the
// golden test compare with the Python peer (benchmarks/peer_gpt_step.py draws
// the same numbers in the same order from the same torch generator).
//
//   torch::manual_seed(0);
//   SyntheticGptBatch x = synthetic_gpt_batch(config.model, config.batch_size, config.caption_dropout);
//   TokenGpt model(config.model);
//   auto adamw = train::make_adamw(model->parameters(), config.optimizer);
//   const double loss = synthetic_gpt_train_step(*model, *adamw, x, config, /*step=*/1);  // the loss before the step
//
// Needs no dataset and no sentence encoder: the use-lite backbone's outputs
// are drawn too.
#pragma once

#include "nec/gpt/model.h"
#include "nec/gpt/training.h"
#include "nec/text/text_encoder.h"

#include <cstdint>

namespace torch::optim {
class Optimizer;
}

namespace nec::gpt {

// Caption pieces per item are drawn in [kSyntheticMinPieces, kSyntheticMaxPieces]: the corpus's captions have
// 8.5 pieces on average (docs/text.md), a batch's longest about twice that.
constexpr int64_t kSyntheticMinPieces = 4;
constexpr int64_t kSyntheticMaxPieces = 16;
// Each item's clip has [kSyntheticMinClipSteps, kSyntheticMaxClipSteps] token steps (2 to 8 s at 30 fps and 4
// frames a step): shorter clips than the window end inside it (end code, padding), longer ones are cropped.
constexpr int64_t kSyntheticMinClipSteps = 15;
constexpr int64_t kSyntheticMaxClipSteps = 60;

struct SyntheticGptBatch {
  GptBatch batch;            // captions empty: inputs, targets, skeleton_features (B, 3 skeleton_dim + 1), drop_text
  text::TextBatch captions;  // use-lite: encoder_features (B, P, 512) zero at padding, unit encoder_sentence, mask
};

// B items made as GptTrainer::batch makes them from a clip's codes: a crop of
// at most max_steps - 1 steps at a random start, targets the next step's codes,
// the end code (layer 0) after a crop that reaches the clip's end, -1 where not
// scored; codes, skeleton features and the caption backbone's outputs random;
// each caption dropped with chance caption_dropout.
SyntheticGptBatch synthetic_gpt_batch(const GptConfig& model, int64_t batch_size, double caption_dropout);

// GptTrainer::step after its batch is made and its captions read, without
// reseeding torch: train mode, zero_grad, teacher_forced_loss (token
// corruption, forward, gpt_loss), backward, train::optimizer_step at the
// schedule's rate of `step` (1-based). Returns the loss before the step.
double synthetic_gpt_train_step(TokenGptImpl& model, torch::optim::Optimizer& optimizer,
                                const SyntheticGptBatch& inputs, const GptTrainConfig& config, int64_t step);

}  // namespace nec::gpt

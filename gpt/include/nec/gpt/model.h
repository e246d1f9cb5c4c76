// The text-to-token transformer (DESIGN.md, Models: GPT): a causal
// transformer over the token steps of a TAT tokenizer, conditioned on a
// caption and on the skeleton the motion is for.
//
//   GptConfig config;  config.codebook_layers = 4;  config.codebook_size = 256;  config.skeleton_dim = 64;
//   TokenGpt gpt(config);
//   GptCondition c = gpt->condition(text_batch, skeleton_features, /*drop_text=*/{});
//   GptLogits out = gpt->forward(c, codes);            // codes (B, S, R) teacher-forced
//   // out.first (B, S + 1, K + 1): layer 0 of steps 0..S, index K = end; out.rest (B, S + 1, R - 1, K)
//
// Sequence: two prefix tokens (the caption's sentence vector, the skeleton's
// features) then one token per step, the sum of one embedding per RVQ layer
// of its codes. The output at the last prefix token predicts step 0, the
// output after step t predicts step t + 1 (or the end). Every layer is pre-norm
// causal self-attention, cross-attention to the caption's per-piece features,
// and a GELU FFN.
//
// Depth head (docs/generation.md, why not MoMask's two transformers): the
// codes of one step are predicted layer by layer from the step's output h:
// layer r reads h plus embeddings of the codes of layers 0..r-1 of the same
// step (the true ones in training, the sampled ones in generation), through
// one shared MLP and a linear head per layer. One causal model, one KV cache.
//
// Classifier-free guidance: a dropped caption (drop_text) is read as a learnt
// null sentence vector and a single learnt null piece; the skeleton stays.
#pragma once

#include "nec/text/text_encoder.h"

#include <ATen/core/Tensor.h>
#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/dropout.h>
#include <torch/nn/modules/embedding.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <vector>

namespace nec::train {
class ConfigVisitor;
}

namespace nec::gpt {

// Hyper-parameters; saved with a model.
struct GptConfig {
  int64_t codebook_layers = 4;   // R of the tokenizer (set from it)
  int64_t codebook_size = 256;   // K of the tokenizer (set from it)
  int64_t skeleton_dim = 64;     // width of the OwO embeddings (set from the tokenizer's encoder)
  int64_t dim = 192;             // token width D, e.g. 192 (CPU) or 512
  int64_t layers = 4;            // transformer layers, e.g. 4 (CPU) or 9
  int64_t heads = 4;             // attention heads; must divide dim
  int64_t feedforward = 768;     // FFN hidden width, e.g. 4 * dim
  int64_t max_steps = 64;        // longest token sequence it reads at once (frames: max_steps x downsampling)
  double dropout = 0.1;          // attention, FFN and embedding dropout, training only
  text::TextEncoderConfig text;  // the caption encoder, trained with the GPT

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
  int64_t end_code() const { return codebook_size; }  // layer 0's extra code: the motion ends
};
void visit_fields(train::ConfigVisitor& v, GptConfig& c);  // train/config_fields.h

// Width of the skeleton features: OwO's skeleton node, the mean and the
// maximum of its joint embeddings, and log(joints) (the joint count tells body plans apart too).
inline int64_t skeleton_feature_width(int64_t skeleton_dim) { return 3 * skeleton_dim + 1; }

// The condition of a batch, computed once per caption and reused at every step.
struct GptCondition {
  at::Tensor prefix;       // (B, 2, D): the caption's and the skeleton's prefix tokens
  at::Tensor memory;       // (B, P, D): per-piece features for cross-attention (the null piece where dropped)
  at::Tensor memory_bias;  // (B, 1, 1, P) additive attention bias, 0 for real pieces

  // Rows `rows` (int64 indices) of every part, e.g. to repeat a condition over samples.
  GptCondition select(const at::Tensor& rows) const;
};

struct GptLogits {
  at::Tensor first;  // (B, N, K + 1) layer 0 of each predicted step; index K = end
  at::Tensor rest;   // (B, N, R - 1, K) layers 1..R-1 (given the true codes below); (B, N, 0, K) for R = 1
};

// Self-attention keys and values of every layer for the tokens read so far.
struct KvCache {
  std::vector<at::Tensor> keys, values;  // per layer (B, H, N, Dh)
  std::vector<at::Tensor> memory_keys, memory_values;  // per layer (B, H, P, Dh), computed once
  at::Tensor memory_bias;                              // (B, 1, 1, P)
  int64_t length() const { return keys.empty() || !keys[0].defined() ? 0 : keys[0].size(2); }
};

namespace detail {
class GptBlockImpl;
}

class TokenGptImpl : public torch::nn::Module {
 public:
  explicit TokenGptImpl(const GptConfig& config);
  const GptConfig& config() const { return config_; }
  text::TextEncoderImpl& text_encoder() { return *text_; }

  // captions (B pieces), skeleton_features (B, skeleton_feature_width), drop_text (B) bool
  // (undefined: none dropped) -> the condition.
  GptCondition condition(const text::TextBatch& captions, const at::Tensor& skeleton_features,
                         const at::Tensor& drop_text);
  // The condition with every caption dropped, for B skeletons.
  GptCondition unconditioned(const at::Tensor& skeleton_features);

  // Teacher forcing: codes (B, S, R) int64 with S < max_steps. Predicts steps
  // 0..S: first (B, S + 1, K + 1); rest from targets (B, S + 1, R) (the codes
  // of each predicted step, whose layers below r condition layer r; the end
  // row's are ignored).
  GptLogits forward(const GptCondition& condition, const at::Tensor& inputs, const at::Tensor& targets);

  // Generation, one step at a time with a KV cache:
  //   KvCache cache;  at::Tensor h = gpt->start(condition, cache, context);   // (B, D) predicts the next step
  //   for each layer r: logits = gpt->layer_logits(h, r, chosen_so_far) ... ; h = gpt->advance(cache, codes);
  // `context` (B, C, R) int64 codes the motion begins with (C may be 0, undefined = none).
  at::Tensor start(const GptCondition& condition, KvCache& cache, const at::Tensor& context);
  // Appends one step of codes (B, R) int64; returns the output that predicts the step after it (B, D).
  at::Tensor advance(KvCache& cache, const at::Tensor& codes);
  // Logits of layer r for outputs h (B, D), given the codes of layers 0..r-1 (B, r) int64 of the same step:
  // (B, K + 1) for r = 0, (B, K) otherwise.
  at::Tensor layer_logits(const at::Tensor& h, int64_t layer, const at::Tensor& lower_codes);

 private:
  // (B, S, D) step tokens of codes (B, S, R) at positions offset.. offset + S - 1 (after the prefix).
  at::Tensor embed_steps(const at::Tensor& codes, int64_t offset);
  // Runs tokens x (B, N, D) through the blocks, appending to the cache; -> (B, N, D) after the final norm.
  at::Tensor run_blocks(const at::Tensor& x, KvCache& cache);

  GptConfig config_;
  text::TextEncoder text_{nullptr};
  torch::nn::Linear sentence_in_{nullptr};   // text output_dim -> D
  torch::nn::Linear pieces_in_{nullptr};     // text dim -> D
  torch::nn::Linear skeleton_in_{nullptr};   // skeleton features -> D
  at::Tensor null_sentence_;                 // (D) a dropped caption's sentence token
  at::Tensor null_piece_;                    // (D) a dropped caption's only piece
  torch::nn::ModuleList code_embeddings_{nullptr};  // R x Embedding(K, D): step tokens
  at::Tensor positions_;                     // (2 + max_steps, D) learnt
  torch::nn::Dropout dropout_{nullptr};
  torch::nn::ModuleList blocks_{nullptr};
  torch::nn::LayerNorm norm_{nullptr};
  torch::nn::ModuleList depth_embeddings_{nullptr};  // (R - 1) x Embedding(K, D): lower codes of the step
  torch::nn::Linear depth_hidden_{nullptr};  // D -> D, shared by every layer
  torch::nn::LayerNorm depth_norm_{nullptr};
  torch::nn::ModuleList heads_{nullptr};     // layer 0: D -> K + 1; layers 1..R-1: D -> K
};
TORCH_MODULE(TokenGpt);

}  // namespace nec::gpt

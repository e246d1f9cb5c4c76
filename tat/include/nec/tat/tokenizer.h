// The topology-agnostic tokenizer TAT (NECromancer 4.3) and the baselines of
// its Table 1, behind one interface.
//
//   TatConfig config;  config.kind = TokenizerKind::NecRvq;  config.joint_embedding_dim = 128;
//   Tokenizer model(config);
//   TokenizerOutput out = model->forward(x.features, x.joint_mask, x.frame_mask, joint_embeddings);
//   // out.reconstruction (B, T, J, 9); out.codes (B, T / r, R)
//   at::Tensor latent = model->encode(features, joint_mask, joint_embeddings);   // (B, T / r, C)
//   QuantizerOutput q = model->quantize(latent, step_mask);
//   at::Tensor back = model->decode(q.quantized, joint_mask, target_embeddings);  // any skeleton
//
// NecRvq / NecVq: per joint MLP(Θ_{t,j}) + Proj(h_j); a virtual joint
// appended at every step, a learnt vector plus the root joint's input;
// `blocks` spatio-temporal blocks, each a temporal conv (stride 2) + ResNet1D per joint, then spatial self-attention over the
// joints and the virtual joint (padded joints masked); only the virtual joint
// goes to the quantizer (T / r steps, r = 2^blocks). Decoder: [z_t ‖ h_j] per
// joint (and z_t as the virtual joint) -> spatial attention -> temporal
// upsampling (x2 per block, ResNet1D) -> linear to the model space's channels. NecVq is NecRvq with a
// single codebook (quantizer.layers = 1).
// ZeroPadRvq: the padding baseline. All joints flattened to channels,
// zero-padded to max_joints (fixed at construction, joint order as in the
// file); the same temporal conv stack, the same quantizer and token budget;
// ignores joint embeddings.
//
// Both kinds read and predict Θ in model space (model_space.h: the root
// displacement in the body's heading frame, turning as a yaw rate, both
// scaled up, the root orientation without its heading); encode converts Θ
// there, decode converts back, so their features in and out are Θ.
//
// Details shared by the kinds: temporal blocks are Conv1d(k4, s2, p1) or
// nearest x2 + Conv1d(k3), each followed by one ResNet1D unit (ReLU, dilated
// k3 conv, ReLU, 1x1 conv, residual); attention layers are pre-norm with a
// GELU FFN of width 2 * dim. The decoders predict offsets from the rest pose
// (identity rot6D) and return zeros at padded joints. A skeleton's output
// does not depend on the skeletons it is batched with (eval mode), nor on the
// features or embeddings given at its padded joints.
#pragma once

#include "nec/tat/quantizer.h"

#include <torch/nn/module.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <memory>
#include <string>

namespace nec::tat {

enum class TokenizerKind { NecRvq, NecVq, ZeroPadRvq };
std::string to_string(TokenizerKind kind);             // "nec-rvq", "nec-vq", "zero-pad-rvq"
TokenizerKind tokenizer_kind_from_string(const std::string& name);  // throws std::invalid_argument

struct TatConfig {
  TokenizerKind kind = TokenizerKind::NecRvq;
  int64_t joint_embedding_dim = 128;  // width of the OwO joint embeddings h_j (unused by ZeroPadRvq)
  int64_t dim = 128;                  // W, width of joint features, e.g. 128 (CPU) or 512
  int64_t blocks = 2;                 // spatio-temporal blocks L; downsampling r = 2^L
  int64_t attention_layers = 1;       // spatial transformer layers per block, e.g. 1 (CPU) or 2 (paper)
  int64_t heads = 4;                  // attention heads; must divide dim
  int64_t max_joints = 0;             // ZeroPadRvq only: channels = 9 * max_joints
  QuantizerConfig quantizer;          // quantizer.code_dim is the latent width C

  int64_t downsampling() const { return int64_t{1} << blocks; }
  // Throws std::invalid_argument naming the first bad field (e.g. NecVq with
  // quantizer.layers != 1, ZeroPadRvq without max_joints).
  void validate() const;
  // One line with every field, e.g. for logs and checkpoint reports.
  std::string to_string() const;
};
void visit_fields(train::ConfigVisitor& v, TatConfig& c);  // train/config_fields.h

struct TokenizerOutput {
  at::Tensor reconstruction;   // (B, T, J, 9)
  at::Tensor codes;            // (B, T / r, R) int64
  at::Tensor commitment_loss;  // scalar
  at::Tensor perplexity;       // (R)
};

namespace detail {
// Encoder and decoder halves of one tokenizer family, defined in tokenizer.cpp.
class EncoderImpl;
class DecoderImpl;
}  // namespace detail

class TokenizerImpl : public torch::nn::Module {
 public:
  explicit TokenizerImpl(const TatConfig& config);

  // features (B, T, J, 9) with T a multiple of downsampling(); joint_mask (B, J)
  // bool; joint_embeddings (B, J, joint_embedding_dim) (undefined for ZeroPadRvq).
  // Returns the latent (B, T / r, C) before quantization.
  at::Tensor encode(const at::Tensor& features, const at::Tensor& joint_mask, const at::Tensor& joint_embeddings);
  // latent (B, S, C), step_mask (B, S) bool or undefined. The output's
  // quantized is (B, S, C) and its codes (B, S, R).
  QuantizerOutput quantize(const at::Tensor& latent, const at::Tensor& step_mask = {});
  // quantized (B, S, C) -> features (B, S * r, J, 9) for the skeletons of joint_mask / joint_embeddings,
  // whose roots face start_heading (B radians about +Y; undefined: 0) at frame 0. The tokens hold no start
  // heading: it turns the body, not its path (model_space.h); see face_forward_at_start.
  at::Tensor decode(const at::Tensor& quantized, const at::Tensor& joint_mask, const at::Tensor& joint_embeddings,
                    const at::Tensor& start_heading = {});
  // codes (B, S, R) -> quantized latent (B, S, C).
  at::Tensor codes_to_latent(const at::Tensor& codes);
  // encode -> quantize (steps whose frames are all padding are masked) -> decode with the input's start heading.
  TokenizerOutput forward(const at::Tensor& features, const at::Tensor& joint_mask, const at::Tensor& frame_mask,
                          const at::Tensor& joint_embeddings);

  // The quantizer's once-per-step EMA update and its ranks (quantizer.h).
  bool update_codebooks() { return quantizer_->update_codebooks(); }
  void set_communicator(const train::Communicator* communicator) { quantizer_->set_communicator(communicator); }

  const TatConfig& config() const { return config_; }

 private:
  TatConfig config_;
  // Registered as "encoder", "quantizer", "decoder" (the checkpoint's tensor
  // name prefixes); the halves are the NEC or the zero-padding family.
  std::shared_ptr<detail::EncoderImpl> encoder_;
  std::shared_ptr<detail::DecoderImpl> decoder_;
  ResidualQuantizer quantizer_{nullptr};
};
TORCH_MODULE(Tokenizer);

}  // namespace nec::tat

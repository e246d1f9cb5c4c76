// Self-supervised pretraining of the OwO graph encoder (NECromancer appendix
// C.3): geometric, topological and semantic tasks on rest-pose skeletons.
//
//   OwoPretrainer model(encoder_config, PretrainConfig{});
//   auto optimizer = train::make_adamw(model->parameters(), train::OptimizerConfig{});
//   optimizer->zero_grad();
//   PretrainLosses l = model->backward(collate(graphs, encoder_config.name_dim));
//   train::optimizer_step(*optimizer, model->parameters(), /*max_grad_norm=*/1.0, /*learning_rate=*/1e-3);
//   // l.total, *l.offset, *l.lca, l.lca_accuracy, ...; afterwards keep model->encoder
//
// Tasks (each switched by a flag; a term that did not run is std::nullopt):
// - offset:      predict each joint's rest offset from h_j (normalized units).
// - pair_offset: predict p_k - p_j from [h_j || h_k] (eq. 13-14, the paper's
//                "distance regression"), on sampled pairs.
// - lca:         pointer over candidate joints k: q = FFN(h_j1 + h_j2), and
//                logit_k = q.key_k / sqrt(D) + a(j1, k) + a(j2, k), softmax over k,
//                cross-entropy against LCA(j1, j2) (eq. 15-18), on sampled pairs.
//                a(i, k) = MLP([h_k || h_i || e_{k->i}]) reads the encoder's final
//                edge k -> i: the LCA is the deepest k that is an ancestor-or-self
//                of both joints, a sum of one term per joint, which the paper's
//                dot product of (h_j1 + h_j2) with key_k alone rarely gets right
//                on long chains (held-out snakes: 0.55 of pairs).
//                By appendix C.4, right answers for all pairs determine the tree.
// - name:        InfoNCE between FFN(h_j) and FFN(name_j) over the batch's named
//                joints (eq. 19-21); skipped without name embeddings.
#pragma once

#include "nec/owo/encoder.h"

#include <optional>

namespace nec::owo {

// Runtime training settings (not saved with the encoder).
struct PretrainConfig {
  bool offset_loss = true;          // per-joint rest offset regression
  bool pair_offset_loss = true;     // pairwise relative position regression (eq. 13-14)
  bool lca_loss = true;             // LCA pointer prediction (eq. 15-18)
  bool name_loss = true;            // joint-name InfoNCE (eq. 19-21); needs name_dim > 0
  double offset_weight = 1.0;       // lambda of the offset term
  double pair_offset_weight = 1.0;  // lambda_geo
  double lca_weight = 1.0;          // lambda_lca
  double name_weight = 0.1;         // lambda_sem
  int64_t pairs_per_skeleton = 64;  // joint pairs sampled per skeleton and step, e.g. 64
  double temperature = 0.1;         // InfoNCE temperature tau, e.g. 0.1

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, PretrainConfig& c);  // train/config_fields.h

struct PretrainLosses {
  double total = 0.0;                 // weighted sum of the terms that ran
  std::optional<double> offset;       // mean squared error of offsets (per joint, summed over xyz)
  std::optional<double> pair_offset;  // same for p_k - p_j of sampled pairs
  std::optional<double> lca;          // mean cross-entropy over sampled pairs
  std::optional<double> name;         // InfoNCE over named joints
  std::optional<double> lca_accuracy; // fraction of sampled pairs whose argmax is the LCA
  std::optional<double> grad_norm;    // global gradient norm before clipping (set by OwoTrainer::step)
};

// a(i, k) of the LCA pointer for every ordered joint pair: an MLP over
// [h_k || h_i || e_{k->i}] whose first layer is split by input, so that no
// (B, J, J, 2 D + edge_dim) concatenation is built.
class PairScoreImpl : public torch::nn::Module {
 public:
  PairScoreImpl(int64_t dim, int64_t edge_dim);

  // joints (B, J, D); joint_edges (B, J, J, edge_dim) incoming, [b, i, k] the
  // edge k -> i (OwoOutput). Returns (B, J, J): [b, i, k] = a(i, k).
  at::Tensor forward(const at::Tensor& joints, const at::Tensor& joint_edges);

 private:
  torch::nn::Linear candidate_{nullptr};  // h_k -> hidden D (with the bias)
  torch::nn::Linear joint_{nullptr};      // h_i -> hidden D
  torch::nn::Linear edge_{nullptr};       // e_{k->i} -> hidden D
  torch::nn::Linear out_{nullptr};        // ReLU(hidden) -> 1
};
TORCH_MODULE(PairScore);

// The encoder with its pretraining heads. Pairs are sampled with torch's
// global generator (torch::manual_seed makes a run repeatable).
class OwoPretrainerImpl : public torch::nn::Module {
 public:
  OwoPretrainerImpl(const OwoConfig& encoder_config, const PretrainConfig& config);

  // The terms on `batch`, with the gradients of `loss_scale` × total added to
  // the parameters' (the caller zeroes them and steps the optimizer:
  // train::optimizer_step). `loss_scale` is a rank's share of a global batch.
  PretrainLosses backward(const GraphBatch& batch, double loss_scale = 1.0);
  // The terms on `batch` without gradients (training mode untouched).
  PretrainLosses evaluate(const GraphBatch& batch);
  // LCA pointer logits for every pair (j1, j2) of every skeleton, without
  // gradients: (B, J, J, J), logits[b, j1, j2, k] scores k as LCA(j1, j2);
  // -inf where k is padding. Throws std::logic_error without the LCA task.
  at::Tensor all_pair_lca_logits(const GraphBatch& batch);
  // Predicted rest offsets (B, J, 3) in the graph's units (zero rows at padding),
  // without gradients. Throws std::logic_error without the offset task.
  at::Tensor predicted_offsets(const GraphBatch& batch);

  const PretrainConfig& config() const { return config_; }

  OwoEncoder encoder{nullptr};

 private:
  struct Terms;
  Terms compute(const GraphBatch& batch);

  PretrainConfig config_;
  torch::nn::Sequential offset_head_{nullptr};       // D -> D -> 3
  torch::nn::Sequential pair_offset_head_{nullptr};  // 2D -> D -> 3 (FFN_geo then W_geo)
  torch::nn::Sequential lca_query_{nullptr};         // D -> D -> D
  torch::nn::Sequential lca_key_{nullptr};           // D -> D -> D
  PairScore lca_ancestry_{nullptr};                  // a(i, k): [D || D || edge_dim] -> D -> 1
  torch::nn::Sequential name_node_{nullptr};         // D -> D -> D
  torch::nn::Sequential name_text_{nullptr};         // E -> D -> D
};
TORCH_MODULE(OwoPretrainer);

}  // namespace nec::owo

// OwO graph encoder (NECromancer appendix C.2): a learned global node plus one
// node per joint, L graph encoder blocks of edge-conditioned graph attention
// with edge updates, each followed by FFN + LayerNorm for nodes and edges.
//
//   OwoConfig config;  config.name_dim = 300;  config.dim = 128;  config.layers = 4;
//   OwoEncoder encoder(config);
//   OwoOutput out = encoder->forward(collate(graphs, config.name_dim));
//   // out.joints (B, J, D): joint identity embeddings, zero at padding
//   // out.skeleton (B, D): the global node, one embedding per skeleton
//   // out.joint_edges (B, J, J, edge_dim): the joint-to-joint edges the last block read
//
// Node j attends to its sources k (the global node and, with tree_edges_only,
// j itself, its parent and its children; otherwise every real joint). Padded
// joints are never a source, so a skeleton's outputs do not depend on what it
// is batched with. Edges are kept in "incoming" layout: edges[b, j, k] is the
// edge k -> j, index 0 being the global node.
#pragma once

#include "nec/owo/graph.h"

#include <torch/nn/module.h>
#include <torch/nn/modules/container/modulelist.h>
#include <torch/nn/modules/container/sequential.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <string>
#include <utility>

namespace nec::owo {

// Hyper-parameters of the encoder; saved with a model.
struct OwoConfig {
  GraphOptions graph;            // featurization; fixes the edge input width
  int64_t name_dim = 0;          // width E of the caller's joint-name embeddings, e.g. 300; 0 = no names
  int64_t dim = 128;             // node width D, e.g. 128 (CPU) or 512
  int64_t layers = 4;            // graph encoder blocks L, e.g. 4
  int64_t heads = 4;             // attention heads H; must divide dim
  int64_t edge_dim = 32;         // edge width, e.g. 32
  int64_t ffn_mult = 2;          // FFN hidden width = ffn_mult * width (nodes and edges)
  double leaky_slope = 0.2;      // LeakyReLU slope of the attention scores (eq. 8)
  bool tree_edges_only = false;  // true: attend along bones + global edges as in the paper; false: all pairs

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
  std::string to_string() const;
};
void visit_fields(train::ConfigVisitor& v, OwoConfig& c);  // train/config_fields.h

struct OwoOutput {
  at::Tensor joints;       // (B, J, D) per-joint embeddings, zero at padding
  at::Tensor skeleton;     // (B, D) global node embedding
  at::Tensor joint_edges;  // (B, J, J, edge_dim) incoming: [b, i, k] is the edge k -> i; zero where i or k is padding
};

// A two-layer perceptron Linear -> ReLU -> Linear, used by the blocks and heads.
torch::nn::Sequential make_mlp(int64_t in, int64_t hidden, int64_t out);

// One graph encoder block: graph attention (eq. 7-10), then FFN + LayerNorm
// (eq. 11-12) on nodes and, the same way, on edges. The last block of an
// encoder skips the edge update (nothing reads its edges).
class GraphEncoderBlockImpl : public torch::nn::Module {
 public:
  GraphEncoderBlockImpl(const OwoConfig& config, bool update_edges);

  // nodes (B, N, D); edges (B, N, N, edge_dim) incoming; attend (B, N, N) bool,
  // attend[b, j, k] = node j may read node k (every row needs one true).
  // Returns the new (nodes, edges), same shapes; edges unchanged without update_edges.
  std::pair<at::Tensor, at::Tensor> forward(const at::Tensor& nodes, const at::Tensor& edges,
                                            const at::Tensor& attend);

 private:
  int64_t heads_;
  double leaky_slope_;
  bool update_edges_;
  torch::nn::Linear node_proj_{nullptr};     // W_node: D -> D
  torch::nn::Linear score_target_{nullptr};  // a^T on W_node h_j: D -> H
  torch::nn::Linear score_source_{nullptr};  // a^T on W_node h_k: D -> H
  torch::nn::Linear score_edge_{nullptr};    // a^T on e_{k->j}: edge_dim -> H
  torch::nn::Linear value_node_{nullptr};    // W_v on h_k: D -> D
  torch::nn::Linear value_edge_{nullptr};    // W_v on e_{k->j}: edge_dim -> D
  torch::nn::Sequential node_ffn_{nullptr};  // D -> ffn_mult D -> D
  torch::nn::LayerNorm node_norm_{nullptr};
  // Edge update, only with update_edges:
  torch::nn::Linear edge_target_{nullptr};   // W_src on W_node h_j: D -> edge_dim
  torch::nn::Linear edge_source_{nullptr};   // W_tgt on W_node h_k: D -> edge_dim
  torch::nn::Sequential edge_ffn_{nullptr};  // edge_dim -> ffn_mult edge_dim -> edge_dim
  torch::nn::LayerNorm edge_norm_{nullptr};
};
TORCH_MODULE(GraphEncoderBlock);

class OwoEncoderImpl : public torch::nn::Module {
 public:
  explicit OwoEncoderImpl(const OwoConfig& config);

  OwoOutput forward(const GraphBatch& batch);
  const OwoConfig& config() const { return config_; }

 private:
  OwoConfig config_;
  torch::nn::Linear node_in_{nullptr};       // [geometry || name] (7 + E) -> D, eq. 3
  at::Tensor global_node_;                   // (D) learned h_global, eq. 4
  torch::nn::Linear edge_target_in_{nullptr};  // h_j -> edge_dim, part of eq. 5-6
  torch::nn::Linear edge_source_in_{nullptr};  // h_k -> edge_dim
  torch::nn::Linear edge_feature_in_{nullptr}; // edge features F -> edge_dim
  at::Tensor global_edge_;                   // (edge_dim) added to every edge touching the global node
  torch::nn::ModuleList blocks_{nullptr};    // L GraphEncoderBlock
};
TORCH_MODULE(OwoEncoder);

}  // namespace nec::owo

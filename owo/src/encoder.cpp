// OwO graph encoder: graph attention with edge features over a global node + joints.
#include "nec/owo/encoder.h"

#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace nec::owo {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("OwoConfig: " + message);
}

}  // namespace

void visit_fields(train::ConfigVisitor& v, OwoConfig& c) {
  v.object("graph", c.graph, "skeleton featurization (fixes the input widths)");
  v.field("name_dim", c.name_dim, "width of the joint-name word vectors; 0 = no names");
  v.field("dim", c.dim, "node width D");
  v.field("layers", c.layers, "graph encoder blocks");
  v.field("heads", c.heads, "attention heads; must divide dim");
  v.field("edge_dim", c.edge_dim, "edge width");
  v.field("ffn_mult", c.ffn_mult, "feed-forward hidden width = ffn_mult x width");
  v.field("leaky_slope", c.leaky_slope, "LeakyReLU slope of the attention scores");
  v.field("tree_edges_only", c.tree_edges_only, "attend along bones + global edges only (the paper); false: all pairs");
}

void OwoConfig::validate() const {
  graph.validate();
  require(name_dim >= 0, "name_dim must be >= 0");
  require(dim >= 1, "dim must be >= 1");
  require(layers >= 1, "layers must be >= 1");
  require(heads >= 1 && dim % heads == 0,
          "heads must divide dim, got heads = " + std::to_string(heads) + ", dim = " + std::to_string(dim));
  require(edge_dim >= 1, "edge_dim must be >= 1");
  require(ffn_mult >= 1, "ffn_mult must be >= 1");
  require(leaky_slope >= 0.0 && leaky_slope < 1.0, "leaky_slope must be in [0, 1)");
}

std::string OwoConfig::to_string() const {
  std::ostringstream out;
  out << "OwoConfig(name_dim=" << name_dim << ", dim=" << dim << ", layers=" << layers << ", heads=" << heads
      << ", edge_dim=" << edge_dim << ", ffn_mult=" << ffn_mult << ", leaky_slope=" << leaky_slope
      << ", tree_edges_only=" << (tree_edges_only ? "true" : "false")
      << ", position_frequencies=" << graph.position_frequencies << ")";
  return out.str();
}

torch::nn::Sequential make_mlp(int64_t in, int64_t hidden, int64_t out) {
  // Built in separate statements: the order in which function arguments are
  // evaluated is unspecified, and it decides which layer gets which random weights.
  torch::nn::Linear first(in, hidden);
  torch::nn::Linear second(hidden, out);
  return torch::nn::Sequential(first, torch::nn::ReLU(), second);
}

GraphEncoderBlockImpl::GraphEncoderBlockImpl(const OwoConfig& config, bool update_edges)
    : heads_(config.heads), leaky_slope_(config.leaky_slope), update_edges_(update_edges) {
  const int64_t d = config.dim, e = config.edge_dim;
  node_proj_ = register_module("node_proj", torch::nn::Linear(torch::nn::LinearOptions(d, d).bias(false)));
  score_target_ = register_module("score_target", torch::nn::Linear(torch::nn::LinearOptions(d, heads_).bias(false)));
  score_source_ = register_module("score_source", torch::nn::Linear(torch::nn::LinearOptions(d, heads_).bias(false)));
  score_edge_ = register_module("score_edge", torch::nn::Linear(torch::nn::LinearOptions(e, heads_).bias(false)));
  value_node_ = register_module("value_node", torch::nn::Linear(d, d));
  value_edge_ = register_module("value_edge", torch::nn::Linear(torch::nn::LinearOptions(e, d).bias(false)));
  node_ffn_ = register_module("node_ffn", make_mlp(d, config.ffn_mult * d, d));
  node_norm_ = register_module("node_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
  if (update_edges_) {
    edge_target_ = register_module("edge_target", torch::nn::Linear(torch::nn::LinearOptions(d, e).bias(false)));
    edge_source_ = register_module("edge_source", torch::nn::Linear(torch::nn::LinearOptions(d, e).bias(false)));
    edge_ffn_ = register_module("edge_ffn", make_mlp(e, config.ffn_mult * e, e));
    edge_norm_ = register_module("edge_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({e})));
  }
}

std::pair<at::Tensor, at::Tensor> GraphEncoderBlockImpl::forward(const at::Tensor& nodes, const at::Tensor& edges,
                                                                 const at::Tensor& attend) {
  const int64_t b = nodes.size(0), n = nodes.size(1), d = nodes.size(2);
  const int64_t head_dim = d / heads_;
  const at::Tensor projected = node_proj_(nodes);  // (B, N, D) W_node h

  // Eq. 8: alpha_{k->j} = softmax_k LeakyReLU(a^T [W h_j || W h_k || e_{k->j}]), per head.
  at::Tensor scores = score_target_(projected).unsqueeze(2) + score_source_(projected).unsqueeze(1) +
                      score_edge_(edges);  // (B, N, N, H)
  scores = torch::leaky_relu(scores, leaky_slope_);
  scores = scores.masked_fill(attend.logical_not().unsqueeze(-1), -std::numeric_limits<float>::infinity());
  const at::Tensor alpha = torch::softmax(scores, /*dim=*/2);  // (B, N, N, H) over sources k

  // Eq. 7, 9: h~_j = sum_k alpha_{k->j} W_v [h_k || e_{k->j}].
  const at::Tensor value_nodes = value_node_(nodes).view({b, n, heads_, head_dim});           // (B, N, H, Dh)
  const at::Tensor value_edges = value_edge_(edges).view({b, n, n, heads_, head_dim});        // (B, N, N, H, Dh)
  at::Tensor messages = torch::einsum("bjkh,bkhd->bjhd", {alpha, value_nodes}) +
                        (alpha.unsqueeze(-1) * value_edges).sum(2);  // (B, N, H, Dh)
  messages = messages.reshape({b, n, d});

  // Eq. 11-12.
  const at::Tensor new_nodes = node_norm_(nodes + torch::relu(node_ffn_->forward(messages)));
  if (!update_edges_) return {new_nodes, edges};

  // Eq. 10, e~_{k->j} = e_{k->j} + W_src W h_j + W_tgt W h_k, then FFN + LayerNorm as for nodes.
  const at::Tensor edge_tilde =
      edges + edge_target_(projected).unsqueeze(2) + edge_source_(projected).unsqueeze(1);  // (B, N, N, E)
  const at::Tensor new_edges = edge_norm_(edges + torch::relu(edge_ffn_->forward(edge_tilde)));
  return {new_nodes, new_edges};
}

OwoEncoderImpl::OwoEncoderImpl(const OwoConfig& config) : config_(config) {
  config_.validate();
  const int64_t d = config_.dim, e = config_.edge_dim;
  node_in_ = register_module("node_in", torch::nn::Linear(kNodeGeometryWidth + config_.name_dim, d));
  global_node_ = register_parameter("global_node", torch::randn({d}) * 0.02);
  edge_target_in_ = register_module("edge_target_in", torch::nn::Linear(torch::nn::LinearOptions(d, e).bias(false)));
  edge_source_in_ = register_module("edge_source_in", torch::nn::Linear(torch::nn::LinearOptions(d, e).bias(false)));
  edge_feature_in_ = register_module("edge_feature_in", torch::nn::Linear(edge_feature_width(config_.graph), e));
  global_edge_ = register_parameter("global_edge", torch::randn({e}) * 0.02);
  blocks_ = register_module("blocks", torch::nn::ModuleList());
  for (int64_t l = 0; l < config_.layers; ++l) {
    blocks_->push_back(GraphEncoderBlock(config_, /*update_edges=*/l + 1 < config_.layers));
  }
}

OwoOutput OwoEncoderImpl::forward(const GraphBatch& batch) {
  const int64_t b = batch.size(), j = batch.max_joints(), n = j + 1;
  const int64_t feature_width = edge_feature_width(config_.graph);
  if (batch.edge_features.size(3) != feature_width || batch.name_embeddings.size(2) != config_.name_dim) {
    throw std::invalid_argument("OwoEncoder: batch has edge features of width " +
                                std::to_string(batch.edge_features.size(3)) + " and names of width " +
                                std::to_string(batch.name_embeddings.size(2)) + ", the model expects " +
                                std::to_string(feature_width) + " and " + std::to_string(config_.name_dim) +
                                " (collate with the model's name_dim and featurize with its GraphOptions)");
  }
  const at::Tensor mask = batch.joint_mask;  // (B, J)

  // Nodes (eq. 3-4): node 0 is the global node.
  const at::Tensor joint_nodes = node_in_(torch::cat({batch.node_geometry, batch.name_embeddings}, -1));  // (B, J, D)
  at::Tensor nodes = torch::cat({global_node_.view({1, 1, -1}).expand({b, 1, config_.dim}), joint_nodes}, 1);

  // Edges (eq. 5-6), incoming layout: edges[b, t, s] is the edge s -> t. Global
  // edges have zero geometric features and a learned marker instead.
  const at::Tensor incoming_features = batch.edge_features.transpose(1, 2);  // (B, J, J, F)
  at::Tensor raw = torch::zeros({b, n, n, feature_width}, incoming_features.options());
  raw.narrow(1, 1, j).narrow(2, 1, j).copy_(incoming_features);
  at::Tensor touches_global = torch::zeros({n, n}, nodes.options());
  touches_global.narrow(0, 0, 1).fill_(1.0);
  touches_global.narrow(1, 0, 1).fill_(1.0);
  at::Tensor edges = edge_feature_in_(raw) + edge_target_in_(nodes).unsqueeze(2) +
                     edge_source_in_(nodes).unsqueeze(1) +
                     touches_global.unsqueeze(-1) * global_edge_;  // (B, N, N, E)

  // Who reads whom: real sources only (the global node always), along bones when asked.
  const at::Tensor source_valid =
      torch::cat({torch::ones({b, 1}, mask.options()), mask}, 1);  // (B, N)
  at::Tensor attend = source_valid.unsqueeze(1).expand({b, n, n});     // (B, N, N)
  if (config_.tree_edges_only) {
    at::Tensor structure = torch::ones({b, n, n}, mask.options());
    structure.narrow(1, 1, j).narrow(2, 1, j).copy_(batch.tree_distance <= 1);
    attend = attend.logical_and(structure);
  }

  for (const auto& block : *blocks_) {
    std::tie(nodes, edges) = block->as<GraphEncoderBlock>()->forward(nodes, edges, attend);
  }

  OwoOutput out;
  const at::Tensor mask_float = mask.to(nodes.scalar_type());
  out.joints = nodes.narrow(1, 1, j) * mask_float.unsqueeze(-1);
  out.skeleton = nodes.select(1, 0);
  // The last block updates no edges: these are the ones it read, the encoder's final pair state.
  const at::Tensor pair_mask = mask_float.unsqueeze(2) * mask_float.unsqueeze(1);  // (B, J, J)
  out.joint_edges = edges.narrow(1, 1, j).narrow(2, 1, j) * pair_mask.unsqueeze(-1);
  return out;
}

}  // namespace nec::owo

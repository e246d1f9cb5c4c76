// OwO pretraining heads and losses (offset, pair offset, LCA pointer, name InfoNCE).
#include "nec/owo/pretrain.h"

#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace nec::owo {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("PretrainConfig: " + message);
}

std::optional<double> value_of(const at::Tensor& term) {
  if (!term.defined()) return std::nullopt;
  return term.item<double>();
}

}  // namespace

void visit_fields(train::ConfigVisitor& v, PretrainConfig& c) {
  v.field("offset_loss", c.offset_loss, "per-joint rest offset regression");
  v.field("pair_offset_loss", c.pair_offset_loss, "relative positions of sampled joint pairs");
  v.field("lca_loss", c.lca_loss, "lowest-common-ancestor prediction of sampled pairs");
  v.field("name_loss", c.name_loss, "joint-name contrastive loss; needs encoder.name_dim > 0");
  v.field("offset_weight", c.offset_weight, "weight of the offset term");
  v.field("pair_offset_weight", c.pair_offset_weight, "weight of the pair offset term");
  v.field("lca_weight", c.lca_weight, "weight of the LCA term");
  v.field("name_weight", c.name_weight, "weight of the name term");
  v.field("pairs_per_skeleton", c.pairs_per_skeleton, "joint pairs sampled per skeleton and step");
  v.field("temperature", c.temperature, "InfoNCE temperature of the name term");
}

void PretrainConfig::validate() const {
  require(offset_loss || pair_offset_loss || lca_loss || name_loss, "every task is switched off");
  require(offset_weight >= 0.0 && pair_offset_weight >= 0.0 && lca_weight >= 0.0 && name_weight >= 0.0,
          "weights must be >= 0");
  require(pairs_per_skeleton >= 1, "pairs_per_skeleton must be >= 1");
  require(temperature > 0.0, "temperature must be positive");
}

PairScoreImpl::PairScoreImpl(int64_t dim, int64_t edge_dim) {
  candidate_ = register_module("candidate", torch::nn::Linear(dim, dim));
  joint_ = register_module("joint", torch::nn::Linear(torch::nn::LinearOptions(dim, dim).bias(false)));
  edge_ = register_module("edge", torch::nn::Linear(torch::nn::LinearOptions(edge_dim, dim).bias(false)));
  out_ = register_module("out", torch::nn::Linear(dim, 1));
}

at::Tensor PairScoreImpl::forward(const at::Tensor& joints, const at::Tensor& joint_edges) {
  // Linear([h_k || h_i || e]) = W_k h_k + W_i h_i + W_e e, broadcast over (i, k).
  const at::Tensor hidden =
      candidate_(joints).unsqueeze(1) + joint_(joints).unsqueeze(2) + edge_(joint_edges);  // (B, J, J, D)
  return out_(torch::relu(hidden)).squeeze(-1);
}

struct OwoPretrainerImpl::Terms {
  at::Tensor total, offset, pair_offset, lca, name, lca_accuracy;  // scalars; undefined when not run
};

OwoPretrainerImpl::OwoPretrainerImpl(const OwoConfig& encoder_config, const PretrainConfig& config)
    : config_(config) {
  config_.validate();
  encoder = register_module("encoder", OwoEncoder(encoder_config));
  const int64_t d = encoder_config.dim;
  if (config_.offset_loss) offset_head_ = register_module("offset_head", make_mlp(d, d, 3));
  if (config_.pair_offset_loss) pair_offset_head_ = register_module("pair_offset_head", make_mlp(2 * d, d, 3));
  if (config_.lca_loss) {
    lca_query_ = register_module("lca_query", make_mlp(d, d, d));
    lca_key_ = register_module("lca_key", make_mlp(d, d, d));
    lca_ancestry_ = register_module("lca_ancestry", PairScore(d, encoder_config.edge_dim));
  }
  if (config_.name_loss && encoder_config.name_dim > 0) {
    name_node_ = register_module("name_node", make_mlp(d, d, d));
    name_text_ = register_module("name_text", make_mlp(encoder_config.name_dim, d, d));
  }
}

OwoPretrainerImpl::Terms OwoPretrainerImpl::compute(const GraphBatch& batch) {
  const OwoOutput out = encoder->forward(batch);
  const at::Tensor& h = out.joints;  // (B, J, D)
  const int64_t b = batch.size(), d = h.size(2);
  const at::Tensor mask = batch.joint_mask;                       // (B, J)
  const at::Tensor mask_float = mask.to(h.scalar_type());
  Terms terms;
  terms.total = torch::zeros({}, h.options());

  if (config_.offset_loss) {
    const at::Tensor error = (offset_head_->forward(h) - batch.rest_offsets).pow(2).sum(-1);  // (B, J)
    terms.offset = (error * mask_float).sum() / mask_float.sum();
    terms.total = terms.total + config_.offset_weight * terms.offset;
  }

  if (config_.pair_offset_loss || config_.lca_loss) {
    // Sampled pairs (j1, j2) of real joints, P per skeleton.
    const int64_t p = config_.pairs_per_skeleton;
    const at::Tensor counts = batch.joint_counts.unsqueeze(1).to(h.scalar_type());  // (B, 1)
    auto sample = [&] {
      at::Tensor rows = torch::rand({b, p}, h.options()) * counts;
      return torch::minimum(rows.floor().to(torch::kInt64), batch.joint_counts.unsqueeze(1) - 1);  // (B, P)
    };
    const at::Tensor first = sample(), second = sample();
    auto gather_rows = [&](const at::Tensor& index) {  // (B, P) -> (B, P, D)
      return h.gather(1, index.unsqueeze(-1).expand({b, p, d}));
    };
    const at::Tensor h_first = gather_rows(first), h_second = gather_rows(second);

    if (config_.pair_offset_loss) {
      auto positions = [&](const at::Tensor& index) {
        return batch.rest_positions.gather(1, index.unsqueeze(-1).expand({b, p, 3}));
      };
      const at::Tensor target = positions(second) - positions(first);  // (B, P, 3)
      const at::Tensor predicted = pair_offset_head_->forward(torch::cat({h_first, h_second}, -1));
      terms.pair_offset = (predicted - target).pow(2).sum(-1).mean();
      terms.total = terms.total + config_.pair_offset_weight * terms.pair_offset;
    }

    if (config_.lca_loss) {
      const at::Tensor query = lca_query_->forward(h_first + h_second);  // (B, P, D)
      const at::Tensor keys = lca_key_->forward(h);                      // (B, J, D)
      const at::Tensor ancestry = lca_ancestry_->forward(out.joints, out.joint_edges);  // (B, J, J)
      const int64_t j = batch.max_joints();
      auto ancestry_rows = [&](const at::Tensor& index) {  // (B, P) -> (B, P, J): a(index, k) over k
        return ancestry.gather(1, index.unsqueeze(-1).expand({b, p, j}));
      };
      at::Tensor logits = torch::bmm(query, keys.transpose(1, 2)) / std::sqrt(static_cast<double>(d)) +
                          ancestry_rows(first) + ancestry_rows(second);  // (B, P, J)
      logits = logits.masked_fill(mask.logical_not().unsqueeze(1), -std::numeric_limits<float>::infinity());
      const at::Tensor lca_rows = batch.lca.gather(1, first.unsqueeze(-1).expand({b, p, j}));
      const at::Tensor target = lca_rows.gather(2, second.unsqueeze(-1)).squeeze(-1);  // (B, P)
      terms.lca = torch::nn::functional::cross_entropy(logits.reshape({b * p, -1}), target.reshape({b * p}));
      terms.lca_accuracy = (logits.argmax(-1) == target).to(h.scalar_type()).mean();
      terms.total = terms.total + config_.lca_weight * terms.lca;
    }
  }

  if (name_node_) {
    const at::Tensor named = mask.logical_and(batch.has_names.unsqueeze(1));  // (B, J)
    if (named.sum().item<int64_t>() >= 2) {
      const at::Tensor node = torch::nn::functional::normalize(
          name_node_->forward(h.index({named})), torch::nn::functional::NormalizeFuncOptions().dim(-1));  // (M, D)
      const at::Tensor text = torch::nn::functional::normalize(
          name_text_->forward(batch.name_embeddings.index({named})),
          torch::nn::functional::NormalizeFuncOptions().dim(-1));  // (M, D)
      const at::Tensor logits = torch::matmul(node, text.transpose(0, 1)) / config_.temperature;  // (M, M)
      const at::Tensor labels = torch::arange(logits.size(0), torch::TensorOptions().dtype(torch::kInt64).device(h.device()));
      terms.name = torch::nn::functional::cross_entropy(logits, labels);
      terms.total = terms.total + config_.name_weight * terms.name;
    }
  }
  return terms;
}

namespace {

PretrainLosses to_losses(const at::Tensor& total, const at::Tensor& offset, const at::Tensor& pair_offset,
                         const at::Tensor& lca, const at::Tensor& name, const at::Tensor& lca_accuracy) {
  PretrainLosses losses;
  losses.total = total.item<double>();
  losses.offset = value_of(offset);
  losses.pair_offset = value_of(pair_offset);
  losses.lca = value_of(lca);
  losses.name = value_of(name);
  losses.lca_accuracy = value_of(lca_accuracy);
  return losses;
}

}  // namespace

PretrainLosses OwoPretrainerImpl::backward(const GraphBatch& batch, double loss_scale) {
  const Terms terms = compute(batch);
  (terms.total * loss_scale).backward();
  return to_losses(terms.total, terms.offset, terms.pair_offset, terms.lca, terms.name, terms.lca_accuracy);
}

PretrainLosses OwoPretrainerImpl::evaluate(const GraphBatch& batch) {
  torch::NoGradGuard no_grad;
  const Terms terms = compute(batch);
  return to_losses(terms.total, terms.offset, terms.pair_offset, terms.lca, terms.name, terms.lca_accuracy);
}

at::Tensor OwoPretrainerImpl::all_pair_lca_logits(const GraphBatch& batch) {
  if (!lca_query_) throw std::logic_error("OwoPretrainer::all_pair_lca_logits: the LCA task is switched off");
  torch::NoGradGuard no_grad;
  const OwoOutput out = encoder->forward(batch);
  const at::Tensor& h = out.joints;  // (B, J, D)
  const int64_t b = h.size(0), j = h.size(1), d = h.size(2);
  const at::Tensor query = lca_query_->forward(h.unsqueeze(2) + h.unsqueeze(1)).reshape({b, j * j, d});  // (B, J*J, D)
  const at::Tensor keys = lca_key_->forward(h);                                                        // (B, J, D)
  at::Tensor logits = torch::bmm(query, keys.transpose(1, 2)) / std::sqrt(static_cast<double>(d));    // (B, J*J, J)
  logits = logits.masked_fill(batch.joint_mask.logical_not().unsqueeze(1), -std::numeric_limits<float>::infinity());
  const at::Tensor ancestry = lca_ancestry_->forward(out.joints, out.joint_edges);  // (B, J, J): a(j1, k), a(j2, k)
  return logits.reshape({b, j, j, j}) + ancestry.unsqueeze(2) + ancestry.unsqueeze(1);
}

at::Tensor OwoPretrainerImpl::predicted_offsets(const GraphBatch& batch) {
  if (!offset_head_) throw std::logic_error("OwoPretrainer::predicted_offsets: the offset task is switched off");
  torch::NoGradGuard no_grad;
  const at::Tensor h = encoder->forward(batch).joints;  // (B, J, D)
  return offset_head_->forward(h) * batch.joint_mask.unsqueeze(-1).to(h.scalar_type());
}

}  // namespace nec::owo

// The text-to-token transformer: condition, teacher-forced forward, cached generation steps.
#include "nec/gpt/model.h"

#include "nec/layers/batched_matmul.h"
#include "nec/layers/transformer.h"
#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::gpt {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("GptConfig: " + message);
}

constexpr int64_t kPrefixTokens = 2;  // sentence, skeleton

// (B, H, N, K) x (B, H, K, M) -> (B, H, N, M): one small product per item and head, which
// layers::batched_matmul does several times faster than torch::matmul's bmm on the CPU.
at::Tensor per_head_product(const at::Tensor& a, const at::Tensor& b) {
  const int64_t groups = a.size(0) * a.size(1);
  return layers::batched_matmul(a.reshape({groups, a.size(2), a.size(3)}), b.reshape({groups, b.size(2), b.size(3)}))
      .view({a.size(0), a.size(1), a.size(2), b.size(3)});
}

}  // namespace

void GptConfig::validate() const {
  require(codebook_layers >= 1 && codebook_size >= 2, "codebook_layers must be >= 1 and codebook_size >= 2");
  require(skeleton_dim >= 1, "skeleton_dim must be >= 1");
  require(dim >= 1 && heads >= 1 && dim % heads == 0, "heads must divide dim");
  require(layers >= 1 && feedforward >= 1, "layers and feedforward must be >= 1");
  require(max_steps >= 2, "max_steps must be >= 2");
  require(dropout >= 0 && dropout < 1, "dropout must be in [0, 1)");
  try {
    text.validate();
  } catch (const std::invalid_argument& e) {
    require(false, std::string("text.") + e.what());
  }
}

void visit_fields(train::ConfigVisitor& v, GptConfig& c) {
  v.field("codebook_layers", c.codebook_layers, "RVQ layers R of the tokenizer (set from --tat)");
  v.field("codebook_size", c.codebook_size, "codes per layer K of the tokenizer (set from --tat)");
  v.field("skeleton_dim", c.skeleton_dim, "width of the OwO embeddings (set from --tat)");
  v.field("dim", c.dim, "token width");
  v.field("layers", c.layers, "transformer layers");
  v.field("heads", c.heads, "attention heads; must divide dim");
  v.field("feedforward", c.feedforward, "FFN hidden width");
  v.field("max_steps", c.max_steps, "longest token sequence read at once; longer motions slide a window");
  v.field("dropout", c.dropout, "dropout in training");
  v.object("text", c.text, "the caption encoder, trained with the GPT");
}

GptCondition GptCondition::select(const at::Tensor& rows) const {
  const at::Tensor index = rows.to(prefix.device());
  return {prefix.index_select(0, index), memory.index_select(0, index), memory_bias.index_select(0, index)};
}

namespace detail {

// Pre-norm causal self-attention (with a KV cache), cross-attention to the caption, FFN.
class GptBlockImpl : public torch::nn::Module {
 public:
  explicit GptBlockImpl(const GptConfig& config) : heads_(config.heads) {
    const int64_t d = config.dim;
    self_norm_ = register_module("self_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
    qkv_ = register_module("qkv", torch::nn::Linear(d, 3 * d));
    self_out_ = register_module("self_out", torch::nn::Linear(d, d));
    cross_norm_ = register_module("cross_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
    query_ = register_module("query", torch::nn::Linear(d, d));
    memory_kv_ = register_module("memory_kv", torch::nn::Linear(d, 2 * d));
    cross_out_ = register_module("cross_out", torch::nn::Linear(d, d));
    ffn_norm_ = register_module("ffn_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
    ffn_in_ = register_module("ffn_in", torch::nn::Linear(d, config.feedforward));
    ffn_out_ = register_module("ffn_out", torch::nn::Linear(config.feedforward, d));
    dropout_ = register_module("dropout", torch::nn::Dropout(config.dropout));
  }

  // (B, N, D) -> (B, H, N, Dh)
  at::Tensor split_heads(const at::Tensor& x) const {
    return x.view({x.size(0), x.size(1), heads_, x.size(2) / heads_}).transpose(1, 2);
  }

  // The memory's keys and values (B, H, P, Dh), once per condition.
  std::pair<at::Tensor, at::Tensor> memory_keys_values(const at::Tensor& memory) {
    const auto kv = memory_kv_(memory).chunk(2, -1);
    return {split_heads(kv[0]), split_heads(kv[1])};
  }

  // x (B, N, D): the next N tokens; keys/values hold the tokens before them and gain these.
  at::Tensor forward(const at::Tensor& x, at::Tensor& keys, at::Tensor& values, const at::Tensor& memory_keys,
                     const at::Tensor& memory_values, const at::Tensor& memory_bias) {
    const int64_t b = x.size(0), n = x.size(1), d = x.size(2);
    const double scale = 1.0 / std::sqrt(static_cast<double>(d / heads_));
    const auto qkv = qkv_(self_norm_(x)).chunk(3, -1);
    const at::Tensor q = split_heads(qkv[0]);
    keys = keys.defined() ? torch::cat({keys, split_heads(qkv[1])}, 2) : split_heads(qkv[1]);
    values = values.defined() ? torch::cat({values, split_heads(qkv[2])}, 2) : split_heads(qkv[2]);
    const int64_t before = keys.size(2) - n;
    at::Tensor scores = per_head_product(q, keys.transpose(-1, -2)) * scale;  // (B, H, N, before + N)
    if (n > 1) {
      // Token i (at before + i) reads keys 0..before + i.
      const at::Tensor future = torch::ones({n, before + n}, x.options().dtype(torch::kBool)).triu(before + 1);
      scores = scores.masked_fill(future, layers::kMaskedScore);
    }
    const at::Tensor attended = per_head_product(torch::softmax(scores, -1), values).transpose(1, 2).reshape({b, n, d});
    at::Tensor y = x + dropout_(self_out_(attended));

    const at::Tensor cq = split_heads(query_(cross_norm_(y)));
    const at::Tensor cross_scores = per_head_product(cq, memory_keys.transpose(-1, -2)) * scale + memory_bias;
    const at::Tensor read = per_head_product(torch::softmax(cross_scores, -1), memory_values).transpose(1, 2).reshape({b, n, d});
    y = y + dropout_(cross_out_(read));
    return y + ffn_out_(dropout_(torch::gelu(ffn_in_(ffn_norm_(y)))));
  }

 private:
  int64_t heads_;
  torch::nn::LayerNorm self_norm_{nullptr}, cross_norm_{nullptr}, ffn_norm_{nullptr};
  torch::nn::Linear qkv_{nullptr}, self_out_{nullptr}, query_{nullptr}, memory_kv_{nullptr}, cross_out_{nullptr};
  torch::nn::Linear ffn_in_{nullptr}, ffn_out_{nullptr};
  torch::nn::Dropout dropout_{nullptr};
};
TORCH_MODULE(GptBlock);

}  // namespace detail

TokenGptImpl::TokenGptImpl(const GptConfig& config) : config_(config) {
  config_.validate();
  const int64_t d = config_.dim, k = config_.codebook_size, r = config_.codebook_layers;
  text_ = register_module("text", text::TextEncoder(config_.text));
  sentence_in_ = register_module("sentence_in", torch::nn::Linear(config_.text.output_dim, d));
  pieces_in_ = register_module("pieces_in", torch::nn::Linear(config_.text.dim, d));
  skeleton_in_ = register_module("skeleton_in", torch::nn::Linear(skeleton_feature_width(config_.skeleton_dim), d));
  null_sentence_ = register_parameter("null_sentence", torch::randn({d}) * 0.02);
  null_piece_ = register_parameter("null_piece", torch::randn({d}) * 0.02);
  code_embeddings_ = register_module("code_embeddings", torch::nn::ModuleList());
  for (int64_t layer = 0; layer < r; ++layer) code_embeddings_->push_back(torch::nn::Embedding(k, d));
  positions_ = register_parameter("positions", torch::randn({kPrefixTokens + config_.max_steps, d}) * 0.02);
  dropout_ = register_module("dropout", torch::nn::Dropout(config_.dropout));
  blocks_ = register_module("blocks", torch::nn::ModuleList());
  for (int64_t layer = 0; layer < config_.layers; ++layer) blocks_->push_back(detail::GptBlock(config_));
  norm_ = register_module("norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
  depth_embeddings_ = register_module("depth_embeddings", torch::nn::ModuleList());
  for (int64_t layer = 1; layer < r; ++layer) depth_embeddings_->push_back(torch::nn::Embedding(k, d));
  depth_hidden_ = register_module("depth_hidden", torch::nn::Linear(d, d));
  depth_norm_ = register_module("depth_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
  heads_ = register_module("heads", torch::nn::ModuleList());
  for (int64_t layer = 0; layer < r; ++layer) heads_->push_back(torch::nn::Linear(d, layer == 0 ? k + 1 : k));
}

GptCondition TokenGptImpl::condition(const text::TextBatch& captions, const at::Tensor& skeleton_features,
                                     const at::Tensor& drop_text) {
  const text::TextEncoding encoded = text_->forward(captions);
  const int64_t b = skeleton_features.size(0);
  at::Tensor sentence = sentence_in_(encoded.sentence);  // (B, D)
  at::Tensor memory = pieces_in_(encoded.features);      // (B, P, D)
  at::Tensor mask = encoded.mask;                        // (B, P)
  if (drop_text.defined()) {
    const at::Tensor drop = drop_text.to(sentence.device()).view({b, 1});
    sentence = torch::where(drop, null_sentence_.expand_as(sentence), sentence);
    // A dropped caption keeps one piece, the null one, at position 0.
    at::Tensor first = torch::zeros_like(mask);
    first.select(1, 0).fill_(true);
    const at::Tensor drop_pieces = drop.expand_as(mask);
    mask = torch::where(drop_pieces, first, mask);
    const at::Tensor null_row = first.unsqueeze(-1).to(memory.scalar_type()) * null_piece_;
    memory = torch::where(drop_pieces.unsqueeze(-1), null_row, memory);
  }
  const at::Tensor prefix = torch::stack({sentence, skeleton_in_(skeleton_features)}, 1);
  return {prefix, memory, layers::padding_bias(mask)};
}

GptCondition TokenGptImpl::unconditioned(const at::Tensor& skeleton_features) {
  const int64_t b = skeleton_features.size(0), d = config_.dim;
  const at::Tensor prefix = torch::stack({null_sentence_.expand({b, d}), skeleton_in_(skeleton_features)}, 1);
  const at::Tensor memory = null_piece_.expand({b, 1, d});
  const at::Tensor mask = torch::ones({b, 1}, skeleton_features.options().dtype(torch::kBool));
  return {prefix, memory, layers::padding_bias(mask)};
}

at::Tensor TokenGptImpl::embed_steps(const at::Tensor& codes, int64_t offset) {
  const int64_t s = codes.size(1);
  if (offset + s > config_.max_steps) {
    throw std::invalid_argument("TokenGpt: " + std::to_string(offset + s) + " steps, more than max_steps = " +
                                std::to_string(config_.max_steps));
  }
  at::Tensor x = positions_.narrow(0, kPrefixTokens + offset, s).unsqueeze(0);
  for (int64_t layer = 0; layer < config_.codebook_layers; ++layer) {
    x = x + code_embeddings_[layer]->as<torch::nn::EmbeddingImpl>()->forward(codes.select(2, layer));
  }
  return x;
}

at::Tensor TokenGptImpl::run_blocks(const at::Tensor& x, KvCache& cache) {
  at::Tensor y = dropout_(x);
  for (size_t i = 0; i < blocks_->size(); ++i) {
    y = blocks_[i]->as<detail::GptBlockImpl>()->forward(y, cache.keys[i], cache.values[i], cache.memory_keys[i],
                                                        cache.memory_values[i], cache.memory_bias);
  }
  return norm_(y);
}

namespace {

// An empty cache for `blocks` layers with the condition's memory keys and values.
void reset_cache(KvCache& cache, torch::nn::ModuleList& blocks, const GptCondition& condition) {
  cache = KvCache{};
  cache.memory_bias = condition.memory_bias;
  for (size_t i = 0; i < blocks->size(); ++i) {
    auto [k, v] = blocks[i]->as<detail::GptBlockImpl>()->memory_keys_values(condition.memory);
    cache.keys.emplace_back();
    cache.values.emplace_back();
    cache.memory_keys.push_back(k);
    cache.memory_values.push_back(v);
  }
}

}  // namespace

GptLogits TokenGptImpl::forward(const GptCondition& condition, const at::Tensor& inputs, const at::Tensor& targets) {
  const int64_t s = inputs.size(1);
  if (targets.size(1) != s + 1) throw std::invalid_argument("TokenGpt::forward: targets must have one step more than inputs");
  KvCache cache;
  reset_cache(cache, blocks_, condition);
  at::Tensor x = condition.prefix + positions_.narrow(0, 0, kPrefixTokens).unsqueeze(0);
  if (s > 0) x = torch::cat({x, embed_steps(inputs, 0)}, 1);
  const at::Tensor h = run_blocks(x, cache).narrow(1, kPrefixTokens - 1, s + 1);  // (B, S + 1, D)

  GptLogits out;
  const int64_t k = config_.codebook_size, r = config_.codebook_layers;
  out.first = heads_[0]->as<torch::nn::LinearImpl>()->forward(
      depth_norm_(torch::gelu(depth_hidden_(h))));
  std::vector<at::Tensor> rest;
  // Padding (-1) and the end code read as code 0; their targets are not scored.
  const at::Tensor given = targets.clamp(0, k - 1);
  at::Tensor depth = h;
  for (int64_t layer = 1; layer < r; ++layer) {
    depth = depth + depth_embeddings_[layer - 1]->as<torch::nn::EmbeddingImpl>()->forward(given.select(2, layer - 1));
    rest.push_back(heads_[layer]->as<torch::nn::LinearImpl>()->forward(depth_norm_(torch::gelu(depth_hidden_(depth)))));
  }
  out.rest = rest.empty() ? torch::zeros({h.size(0), s + 1, 0, k}, h.options()) : torch::stack(rest, 2);
  return out;
}

at::Tensor TokenGptImpl::start(const GptCondition& condition, KvCache& cache, const at::Tensor& context) {
  reset_cache(cache, blocks_, condition);
  at::Tensor x = condition.prefix + positions_.narrow(0, 0, kPrefixTokens).unsqueeze(0);
  if (context.defined() && context.size(1) > 0) x = torch::cat({x, embed_steps(context, 0)}, 1);
  const at::Tensor y = run_blocks(x, cache);
  return y.select(1, y.size(1) - 1);
}

at::Tensor TokenGptImpl::advance(KvCache& cache, const at::Tensor& codes) {
  const int64_t offset = cache.length() - kPrefixTokens;
  const at::Tensor y = run_blocks(embed_steps(codes.unsqueeze(1), offset), cache);
  return y.select(1, 0);
}

at::Tensor TokenGptImpl::layer_logits(const at::Tensor& h, int64_t layer, const at::Tensor& lower_codes) {
  if (layer < 0 || layer >= config_.codebook_layers) throw std::invalid_argument("TokenGpt: no layer " + std::to_string(layer));
  at::Tensor depth = h;
  for (int64_t below = 0; below < layer; ++below) {
    depth = depth + depth_embeddings_[below]->as<torch::nn::EmbeddingImpl>()->forward(lower_codes.select(1, below));
  }
  return heads_[layer]->as<torch::nn::LinearImpl>()->forward(depth_norm_(torch::gelu(depth_hidden_(depth))));
}

}  // namespace nec::gpt

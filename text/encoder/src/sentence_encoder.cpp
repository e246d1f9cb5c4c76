// The pretrained sentence encoder: the TF.js graph's weights and constants read by name, run in LibTorch.
#include "nec/text/sentence_encoder.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <string_view>

namespace nec::text {
namespace {

namespace fs = std::filesystem;

// The graph's weights manifest over the concatenated shards.
class GraphWeights {
 public:
  explicit GraphWeights(const std::string& dir) : model_path_((fs::path(dir) / "model.json").string()) {
    if (!fs::exists(model_path_)) fail("is missing");
    nlohmann::json model;
    try {
      model = nlohmann::json::parse(read_file(model_path_, size_t{64} << 20));
    } catch (const nlohmann::json::exception& e) {
      fail(std::string("is not JSON (") + e.what() + ")");
    }
    if (!model.contains("weightsManifest") || !model["weightsManifest"].is_array() || model["weightsManifest"].size() != 1) {
      fail("has no single weightsManifest group");
    }
    const nlohmann::json& group = model["weightsManifest"][0];
    read_shards(dir, group.at("paths"));
    size_t offset = 0;
    for (const auto& entry : group.at("weights")) {
      Entry weight;
      weight.dtype = entry.at("dtype").get<std::string>();
      if (weight.dtype != "float32" && weight.dtype != "int32") fail("holds a weight of type " + weight.dtype);
      if (entry.contains("quantization")) fail("holds quantized weights");
      int64_t count = 1;
      for (const auto& size : entry.at("shape")) {
        weight.shape.push_back(size.get<int64_t>());
        count *= weight.shape.back();
      }
      weight.offset = offset;
      offset += static_cast<size_t>(count) * 4;
      entries_[entry.at("name").get<std::string>()] = weight;
    }
    if (offset != static_cast<size_t>(bytes_.numel())) {
      fail("lists " + std::to_string(offset) + " bytes of weights, its shards hold " + std::to_string(bytes_.numel()));
    }
  }

  // The float weight whose name ends with `tail`: exactly one must.
  at::Tensor tensor(std::string_view tail, std::vector<int64_t> shape = {}) const {
    const auto& [name, entry] = find(tail);
    if (entry.dtype != "float32") fail(name + " is not float32");
    if (!shape.empty() && entry.shape != shape) fail(name + " has an unexpected shape");
    const int64_t count = c10::multiply_integers(entry.shape);
    // A view of the shards' bytes (every weight starts at a multiple of 4): the weights are not copied.
    return bytes_.narrow(0, static_cast<int64_t>(entry.offset), count * 4).view(torch::kFloat32).view(entry.shape);
  }
  double scalar(std::string_view tail) const {
    const auto& [name, entry] = find(tail);
    if (entry.shape.size() > 1 || (entry.shape.size() == 1 && entry.shape[0] != 1)) fail(name + " is not a scalar");
    const uint8_t* data = bytes_.data_ptr<uint8_t>() + entry.offset;
    if (entry.dtype == "float32") {
      float value;
      std::memcpy(&value, data, 4);
      return value;
    }
    int32_t value;
    std::memcpy(&value, data, 4);
    return value;
  }
  bool has(std::string_view tail) const { return !named(tail).empty(); }
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(model_path_, 0, problem + "; not the sentence encoder nec reads (" + kSentenceEncoderHint + ")");
  }

 private:
  // The shards, end to end, as one byte tensor that the weights view: mapped from the files where each shard
  // but the last fills whole pages (as the package's 4-MiB shards do), so that loading copies nothing and a
  // caption touches only its pieces' rows of the 8,000-piece embedding; else read.
  void read_shards(const std::string& dir, const nlohmann::json& shards) {
    std::vector<std::string> paths;
    std::vector<int64_t> sizes;
    for (const auto& shard : shards) {
      const std::string path = (fs::path(dir) / shard.get<std::string>()).string();
      std::error_code ec;
      const auto size = fs::file_size(path, ec);
      if (ec) throw InputError(path, 0, std::string("a weight shard is missing; ") + kSentenceEncoderHint);
      paths.push_back(path);
      sizes.push_back(static_cast<int64_t>(size));
    }
    const int64_t total = std::accumulate(sizes.begin(), sizes.end(), int64_t{0});
    if (std::optional<MappedFile> joined = MappedFile::open_joined(paths); joined && joined->size() > 0) {
      auto owner = std::make_shared<MappedFile>(std::move(*joined));
      // Read-only pages: the weights are buffers of a frozen graph, never written.
      bytes_ = torch::from_blob(const_cast<unsigned char*>(owner->data()), {static_cast<int64_t>(owner->size())},
                                [owner](void*) {}, torch::kUInt8);
      return;
    }
    bytes_ = torch::empty({total}, torch::kUInt8);
    char* out = reinterpret_cast<char*>(bytes_.data_ptr<uint8_t>());
    for (size_t i = 0; i < paths.size(); ++i) {
      std::ifstream in(paths[i], std::ios::binary);
      if (!in.read(out, sizes[i])) throw InputError(paths[i], 0, "cannot read the weight shard; " + std::string(kSentenceEncoderHint));
      out += sizes[i];
    }
  }

  struct Entry {
    std::string dtype;
    std::vector<int64_t> shape;
    size_t offset = 0;
  };
  // Every weight whose name ends with `tail`.
  std::vector<const std::pair<const std::string, Entry>*> named(std::string_view tail) const {
    std::vector<const std::pair<const std::string, Entry>*> out;
    for (const auto& entry : entries_) {
      const std::string& name = entry.first;
      if (name.size() >= tail.size() && name.compare(name.size() - tail.size(), tail.size(), tail) == 0) out.push_back(&entry);
    }
    return out;
  }
  const std::pair<const std::string, Entry>& find(std::string_view tail) const {
    const auto found = named(tail);
    if (found.size() != 1) fail("has " + std::to_string(found.size()) + " weights named *" + std::string(tail));
    return *found.front();
  }

  std::string model_path_;
  at::Tensor bytes_;
  std::map<std::string, Entry> entries_;
};

at::Tensor matrix(const at::Tensor& kernel) {  // a 1x1 convolution's [1, 1, in, out] kernel as (in, out)
  return kernel.dim() == 4 ? kernel.reshape({kernel.size(2), kernel.size(3)}) : kernel;
}

// A layer's weights are named in its own scope ("Encode/Layer_0/...") or its ops' ("TransformerStack/Layer_0/...").
std::string layer_scope(int layer) { return "/Encode/Layer_" + std::to_string(layer) + "/TransformerLayer/"; }
std::string ops_scope(int layer) { return "/TransformerStack/Layer_" + std::to_string(layer) + "/TransformerLayer/"; }

}  // namespace

SentenceEncoderImpl::SentenceEncoderImpl(const std::string& dir)
    : pieces_(SentencePieces::load((fs::path(dir) / "vocab.json").string())) {
  const GraphWeights graph(dir);
  embeddings_ = register_buffer("embeddings", graph.tensor("module/Embeddings_en"));
  if (embeddings_.dim() != 2 || embeddings_.size(0) < pieces_.size()) graph.fail("its embedding table does not cover vocab.json");
  inverse_timescales_ =
      register_buffer("inverse_timescales", graph.tensor("/AddTimingSignal/TimingSignal/ExpandDims_1").reshape({-1}));
  if (2 * inverse_timescales_.size(0) != embeddings_.size(1)) graph.fail("its timing signal is not as wide as the embeddings");
  max_pieces_ = static_cast<int64_t>(graph.scalar("/ClipToMaxLength/Less/y"));
  norm_epsilon_ = graph.scalar("/layer_norm/Cast/x");
  l2_epsilon_ = graph.scalar("/l2_normalize/Maximum/y");
  padding_bias_ = graph.scalar("/attention_bias_ignore_padding/mul/y");
  const int64_t heads = static_cast<int64_t>(graph.scalar("/split_heads/split_last_dimension/Reshape/shape/2"));

  for (int k = 0; graph.has(layer_scope(k) + "MultiheadAttention/qkv_transform_single/kernel/part_0"); ++k) {
    const std::string own = layer_scope(k), ops = ops_scope(k), name = "layer" + std::to_string(k) + "_";
    const auto weight = [&](const std::string& buffer_name, const std::string& tail) {
      return register_buffer(name + buffer_name, matrix(graph.tensor(tail)));
    };
    SentenceEncoderLayer layer;
    layer.heads = heads;
    layer.head_dim = static_cast<int64_t>(graph.scalar(ops + "MultiheadAttention/split_heads/split_last_dimension/Reshape/shape/3"));
    layer.query_scale = graph.scalar(ops + "MultiheadAttention/mul/y");
    const std::string norm = "layer_prepostprocess/layer_norm/layer_norm_", concat = "/ConcatPartitions/concat";
    layer.norm_scale = weight("norm_scale", own + norm + "scale" + concat);
    layer.norm_bias = weight("norm_bias", own + norm + "bias" + concat);
    layer.qkv_weight = weight("qkv_weight", own + "MultiheadAttention/qkv_transform_single/kernel/part_0");
    layer.qkv_bias = weight("qkv_bias", own + "MultiheadAttention/qkv_transform_single/bias" + concat);
    layer.output_weight = weight("output_weight", own + "MultiheadAttention/output_transform_single/kernel/part_0");
    layer.output_bias = weight("output_bias", own + "MultiheadAttention/output_transform_single/bias" + concat);
    layer.projected_residual = graph.has(own + "dense/kernel" + concat);
    if (layer.projected_residual) {
      layer.residual_weight = weight("residual_weight", own + "dense/kernel" + concat);
      layer.residual_bias = weight("residual_bias", own + "dense/bias" + concat);
    }
    layer.ffn_norm_scale = weight("ffn_norm_scale", own + "FFN/" + norm + "scale" + concat);
    layer.ffn_norm_bias = weight("ffn_norm_bias", own + "FFN/" + norm + "bias" + concat);
    layer.ffn_in_weight = weight("ffn_in_weight", ops + "FFN/conv1/Tensordot/Reshape_1");
    layer.ffn_in_bias = weight("ffn_in_bias", own + "FFN/conv1/bias" + concat);
    layer.ffn_out_weight = weight("ffn_out_weight", ops + "FFN/conv2/Tensordot/Reshape_1");
    layer.ffn_out_bias = weight("ffn_out_bias", own + "FFN/conv2/bias" + concat);

    const int64_t in = layers_.empty() ? embeddings_.size(1) : layers_.back().output_weight.size(1);
    const int64_t width = heads * layer.head_dim;
    if (layer.qkv_weight.sizes() != at::IntArrayRef{in, 3 * width} || layer.output_weight.size(0) != width ||
        (!layer.projected_residual && layer.output_weight.size(1) != in)) {
      graph.fail("layer " + std::to_string(k) + "'s attention weights do not fit its heads and input");
    }
    layers_.push_back(std::move(layer));
  }
  if (layers_.empty()) graph.fail("has no transformer layers");
  dim_ = layers_.back().output_weight.size(1);
  pool_weight_ = register_buffer("pool_weight", graph.tensor("/hidden_layers/tanh_layer_0/weights", {dim_, dim_}));
  pool_bias_ = register_buffer("pool_bias", graph.tensor("/hidden_layers/tanh_layer_0/bias", {dim_}));
}

void SentenceEncoderImpl::cut_pieces(std::vector<std::vector<int>>& pieces) const {
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (pieces[i].empty()) throw InputError("sentence " + std::to_string(i + 1) + " is empty: the sentence encoder needs text");
    if (static_cast<int64_t>(pieces[i].size()) > max_pieces_) pieces[i].resize(static_cast<size_t>(max_pieces_));
  }
}

SentenceEncoding SentenceEncoderImpl::forward(const at::Tensor& ids, const at::Tensor& mask) const {
  const int64_t batch = ids.size(0), length = ids.size(1);
  const at::Tensor real = mask.unsqueeze(-1).to(embeddings_.scalar_type());  // (B, P, 1)
  const at::Tensor angles = torch::arange(length, inverse_timescales_.options()).unsqueeze(1) * inverse_timescales_;
  const at::Tensor timing = torch::cat({angles.sin(), angles.cos()}, 1);       // (P, width)
  at::Tensor x = (2.0 * embeddings_.index_select(0, ids.reshape({-1}).clamp_min(0)).view({batch, length, -1}) + timing) * real;
  const at::Tensor key_bias = ((1.0 - mask.to(x.scalar_type())) * padding_bias_).view({batch, 1, 1, length});
  for (const SentenceEncoderLayer& layer : layers_) {
    const at::Tensor normed = torch::layer_norm(x, {x.size(-1)}, layer.norm_scale, layer.norm_bias, norm_epsilon_);
    const std::vector<at::Tensor> qkv = torch::addmm(layer.qkv_bias, normed.reshape({batch * length, -1}), layer.qkv_weight)
                                            .view({batch, length, 3, layer.heads, layer.head_dim})
                                            .permute({2, 0, 3, 1, 4})
                                            .unbind(0);  // each (B, H, P, head_dim)
    const at::Tensor weights = torch::softmax(torch::matmul(qkv[0] * layer.query_scale, qkv[1].transpose(-1, -2)) + key_bias, -1);
    const at::Tensor context = torch::matmul(weights, qkv[2]).transpose(1, 2).reshape({batch * length, -1});
    const at::Tensor attended = torch::addmm(layer.output_bias, context, layer.output_weight).view({batch, length, -1});
    const at::Tensor residual =
        layer.projected_residual ? torch::addmm(layer.residual_bias, x.reshape({batch * length, -1}), layer.residual_weight)
                                           .view({batch, length, -1}) * real
                                 : x;
    x = attended + residual;
    const at::Tensor hidden = torch::relu(torch::addmm(
        layer.ffn_in_bias, torch::layer_norm(x, {x.size(-1)}, layer.ffn_norm_scale, layer.ffn_norm_bias, norm_epsilon_)
                               .reshape({batch * length, -1}),
        layer.ffn_in_weight));
    x = x + torch::addmm(layer.ffn_out_bias, hidden, layer.ffn_out_weight).view({batch, length, -1}) * real;
  }
  SentenceEncoding out;
  out.features = x * real;
  out.mask = mask;
  const at::Tensor pooled = out.features.sum(1) / real.sum(1).clamp_min(1.0);
  const at::Tensor dense = torch::tanh(torch::addmm(pool_bias_, pooled, pool_weight_));
  out.sentence = dense * torch::rsqrt(dense.square().sum(-1, true).clamp_min(l2_epsilon_));
  return out;
}

SentenceEncoding SentenceEncoderImpl::encode(const std::vector<std::string>& sentences) const {
  std::vector<std::vector<int>> pieces;
  pieces.reserve(sentences.size());
  for (const std::string& sentence : sentences) pieces.push_back(pieces_.encode(sentence));
  return encode_pieces(std::move(pieces));
}

SentenceEncoding SentenceEncoderImpl::encode_pieces(std::vector<std::vector<int>> pieces) const {
  cut_pieces(pieces);
  size_t longest = 0;
  for (const auto& ids : pieces) longest = std::max(longest, ids.size());
  const int64_t batch = static_cast<int64_t>(pieces.size()), length = static_cast<int64_t>(longest);
  at::Tensor ids = torch::zeros({batch, length}, torch::kInt64);
  at::Tensor mask = torch::zeros({batch, length}, torch::kBool);
  int64_t* id = ids.data_ptr<int64_t>();
  bool* real = mask.data_ptr<bool>();
  for (int64_t b = 0; b < batch; ++b) {
    const std::vector<int>& row = pieces[static_cast<size_t>(b)];
    std::copy(row.begin(), row.end(), id + b * length);
    std::fill(real + b * length, real + b * length + static_cast<int64_t>(row.size()), true);
  }
  torch::NoGradGuard no_grad;
  const c10::Device device = embeddings_.device();
  return forward(ids.to(device), mask.to(device));
}

}  // namespace nec::text

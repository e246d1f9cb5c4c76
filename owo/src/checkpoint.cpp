// OwO checkpoint directories: config.json + tensors.pt, atomic save, checked load.
#include "nec/owo/checkpoint.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <c10/util/Exception.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace nec::owo {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kArchitecture = "OwoPretrainer";
constexpr const char* kConfigFile = "config.json";
constexpr const char* kTensorFile = "tensors.pt";
constexpr const char* kTrainHint = "run `nec train owo` to make one";

json to_json(const OwoConfig& c) {
  return {{"graph",
           {{"normalize_scale", c.graph.normalize_scale},
            {"position_frequencies", c.graph.position_frequencies},
            {"depth_scale", c.graph.depth_scale},
            {"children_scale", c.graph.children_scale},
            {"max_tree_distance", c.graph.max_tree_distance}}},
          {"name_dim", c.name_dim},
          {"dim", c.dim},
          {"layers", c.layers},
          {"heads", c.heads},
          {"edge_dim", c.edge_dim},
          {"ffn_mult", c.ffn_mult},
          {"leaky_slope", c.leaky_slope},
          {"tree_edges_only", c.tree_edges_only}};
}

json to_json(const PretrainConfig& c) {
  return {{"offset_loss", c.offset_loss},
          {"pair_offset_loss", c.pair_offset_loss},
          {"lca_loss", c.lca_loss},
          {"name_loss", c.name_loss},
          {"offset_weight", c.offset_weight},
          {"pair_offset_weight", c.pair_offset_weight},
          {"lca_weight", c.lca_weight},
          {"name_weight", c.name_weight},
          {"pairs_per_skeleton", c.pairs_per_skeleton},
          {"temperature", c.temperature}};
}

// Reads config.json fields, naming the missing or mistyped one.
class ConfigReader {
 public:
  explicit ConfigReader(std::string file) : file_(std::move(file)) {}

  const json& object(const json& parent, const std::string& key, const std::string& where) const {
    const json& value = field(parent, key, where);
    if (!value.is_object()) fail(where + key, "an object");
    return value;
  }
  template <typename T>
  void read(const json& parent, const std::string& key, const std::string& where, T& out) const {
    const json& value = field(parent, key, where);
    if constexpr (std::is_same_v<T, bool>) {
      if (!value.is_boolean()) fail(where + key, "true or false");
    } else if constexpr (std::is_integral_v<T>) {
      if (!value.is_number_integer()) fail(where + key, "an integer");
    } else if constexpr (std::is_floating_point_v<T>) {
      if (!value.is_number()) fail(where + key, "a number");
    } else {
      if (!value.is_string()) fail(where + key, "a string");
    }
    out = value.get<T>();
  }
  [[noreturn]] void fail(const std::string& problem) const { throw InputError(file_, 0, problem); }

 private:
  const json& field(const json& parent, const std::string& key, const std::string& where) const {
    const auto it = parent.find(key);
    if (it == parent.end()) fail("field '" + where + key + "' is missing; the checkpoint is damaged, " + kTrainHint);
    return *it;
  }
  [[noreturn]] void fail(const std::string& name, const std::string& expected) const {
    fail("field '" + name + "' must be " + expected + "; the checkpoint is damaged, " + kTrainHint);
  }
  std::string file_;
};

OwoConfig read_encoder_config(const ConfigReader& reader, const json& root) {
  const json& e = reader.object(root, "encoder", "");
  const json& g = reader.object(e, "graph", "encoder.");
  OwoConfig c;
  reader.read(g, "normalize_scale", "encoder.graph.", c.graph.normalize_scale);
  reader.read(g, "position_frequencies", "encoder.graph.", c.graph.position_frequencies);
  reader.read(g, "depth_scale", "encoder.graph.", c.graph.depth_scale);
  reader.read(g, "children_scale", "encoder.graph.", c.graph.children_scale);
  reader.read(g, "max_tree_distance", "encoder.graph.", c.graph.max_tree_distance);
  reader.read(e, "name_dim", "encoder.", c.name_dim);
  reader.read(e, "dim", "encoder.", c.dim);
  reader.read(e, "layers", "encoder.", c.layers);
  reader.read(e, "heads", "encoder.", c.heads);
  reader.read(e, "edge_dim", "encoder.", c.edge_dim);
  reader.read(e, "ffn_mult", "encoder.", c.ffn_mult);
  reader.read(e, "leaky_slope", "encoder.", c.leaky_slope);
  reader.read(e, "tree_edges_only", "encoder.", c.tree_edges_only);
  return c;
}

PretrainConfig read_pretrain_config(const ConfigReader& reader, const json& root) {
  const json& p = reader.object(root, "pretrain", "");
  PretrainConfig c;
  reader.read(p, "offset_loss", "pretrain.", c.offset_loss);
  reader.read(p, "pair_offset_loss", "pretrain.", c.pair_offset_loss);
  reader.read(p, "lca_loss", "pretrain.", c.lca_loss);
  reader.read(p, "name_loss", "pretrain.", c.name_loss);
  reader.read(p, "offset_weight", "pretrain.", c.offset_weight);
  reader.read(p, "pair_offset_weight", "pretrain.", c.pair_offset_weight);
  reader.read(p, "lca_weight", "pretrain.", c.lca_weight);
  reader.read(p, "name_weight", "pretrain.", c.name_weight);
  reader.read(p, "pairs_per_skeleton", "pretrain.", c.pairs_per_skeleton);
  reader.read(p, "temperature", "pretrain.", c.temperature);
  return c;
}

// Every parameter and buffer of `model` by dotted name, e.g. "encoder.blocks.0.node_proj.weight".
std::vector<std::pair<std::string, at::Tensor>> named_tensors(OwoPretrainerImpl& model) {
  std::vector<std::pair<std::string, at::Tensor>> out;
  for (const auto& item : model.named_parameters()) out.emplace_back(item.key(), item.value());
  for (const auto& item : model.named_buffers()) out.emplace_back(item.key(), item.value());
  return out;
}

std::string shape_text(at::IntArrayRef sizes) {
  std::string text = "[";
  for (size_t i = 0; i < sizes.size(); ++i) text += (i ? ", " : "") + std::to_string(sizes[i]);
  return text + "]";
}

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

fs::path sibling(const fs::path& dir, const std::string& tag) {
  std::random_device entropy;
  return dir.parent_path() / ("." + dir.filename().string() + "." + tag + std::to_string(entropy()));
}

}  // namespace

void save_owo_checkpoint(const std::string& dir, OwoPretrainerImpl& model, const OwoCheckpointInfo& info) {
  fs::path target = fs::path(dir);
  if (target.filename().empty()) target = target.parent_path();  // "runs/owo/" -> "runs/owo"
  std::error_code ec;
  const bool exists = fs::exists(target, ec);
  if (exists && (!fs::is_directory(target, ec) ||
                 (!fs::is_empty(target, ec) && !fs::exists(target / kConfigFile, ec)))) {
    throw std::runtime_error(dir + ": exists and is not an OwO checkpoint directory; not replacing it");
  }
  if (!target.parent_path().empty()) fs::create_directories(target.parent_path(), ec);

  const fs::path temp = sibling(target, "tmp");
  auto remove_temp = [&] {
    std::error_code ignored;
    fs::remove_all(temp, ignored);
  };
  try {
    if (!fs::create_directory(temp, ec)) throw std::runtime_error(temp.string() + ": cannot create: " + ec.message());
    const json config = {{"format", kOwoCheckpointFormat},
                         {"version", kOwoCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"encoder", to_json(model.encoder->config())},
                         {"pretrain", to_json(model.config())},
                         {"training_step", info.training_step},
                         {"data", info.data},
                         {"tensors", kTensorFile}};
    write_file_atomic((temp / kConfigFile).string(), config.dump(2) + "\n");
    torch::serialize::OutputArchive archive;
    {
      torch::NoGradGuard no_grad;
      for (const auto& [name, tensor] : named_tensors(model)) archive.write(name, tensor.detach().to(torch::kCPU));
    }
    archive.save_to((temp / kTensorFile).string());

    // Swap into place: the old checkpoint (if any) moves aside first, and is
    // removed only once the new one is in place.
    fs::path old;
    if (exists) {
      old = sibling(target, "old");
      fs::rename(target, old, ec);
      if (ec) throw std::runtime_error(dir + ": cannot move the old checkpoint aside: " + ec.message());
    }
    fs::rename(temp, target, ec);
    if (ec) {
      std::error_code ignored;
      if (!old.empty()) fs::rename(old, target, ignored);
      throw std::runtime_error(dir + ": cannot move the written checkpoint into place: " + ec.message());
    }
    if (!old.empty()) fs::remove_all(old, ec);
  } catch (const c10::Error& error) {
    remove_temp();
    throw std::runtime_error(dir + ": cannot write the tensors: " + first_line(error.what()));
  } catch (...) {
    remove_temp();
    throw;
  }
}

LoadedOwoCheckpoint load_owo_checkpoint(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(dir, 0, std::string("no such checkpoint directory; ") + kTrainHint);
  }
  const std::string config_path = (fs::path(dir) / kConfigFile).string();
  if (!fs::exists(config_path, ec)) {
    throw InputError(config_path, 0, std::string("missing: not an OwO checkpoint; ") + kTrainHint);
  }
  const ConfigReader reader(config_path);
  json root;
  try {
    root = json::parse(read_file(config_path, size_t{1} << 24));
  } catch (const json::parse_error& error) {
    reader.fail(std::string("not valid JSON (") + error.what() + "); the checkpoint is damaged, " + kTrainHint);
  }
  if (!root.is_object()) reader.fail(std::string("not an OwO checkpoint (no JSON object); ") + kTrainHint);

  const auto format = root.find("format");
  if (format == root.end() || !format->is_string() || *format != kOwoCheckpointFormat) {
    const std::string found = format == root.end() ? "none" : "'" + (format->is_string() ? format->get<std::string>() : format->dump()) + "'";
    reader.fail("not an OwO checkpoint (format " + found + ", expected '" + kOwoCheckpointFormat + "'); " + kTrainHint);
  }
  const auto version = root.find("version");
  if (version == root.end() || !version->is_number_integer()) {
    reader.fail(std::string("field 'version' is missing or not an integer; the checkpoint is damaged, ") + kTrainHint);
  }
  if (version->get<int64_t>() != kOwoCheckpointVersion) {
    reader.fail("was written by format version " + std::to_string(version->get<int64_t>()) + "; this nec reads version " +
                std::to_string(kOwoCheckpointVersion) + ": load it with the nec that wrote it, or retrain (" + kTrainHint +
                ")");
  }
  std::string architecture;
  reader.read(root, "architecture", "", architecture);
  if (architecture != kArchitecture) {
    reader.fail("architecture '" + architecture + "' is not " + kArchitecture + "; " + kTrainHint);
  }
  const OwoConfig encoder_config = read_encoder_config(reader, root);
  const PretrainConfig pretrain_config = read_pretrain_config(reader, root);
  LoadedOwoCheckpoint loaded;
  reader.read(root, "training_step", "", loaded.info.training_step);
  reader.read(root, "data", "", loaded.info.data);
  std::string tensor_file;
  reader.read(root, "tensors", "", tensor_file);
  if (tensor_file.empty() || fs::path(tensor_file).has_parent_path()) {
    reader.fail("field 'tensors' must name a file inside the checkpoint directory");
  }

  try {
    encoder_config.validate();
    pretrain_config.validate();
    loaded.model = OwoPretrainer(encoder_config, pretrain_config);
  } catch (const std::invalid_argument& error) {
    reader.fail(std::string(error.what()) + "; the checkpoint is damaged, " + kTrainHint);
  }

  const std::string tensor_path = (fs::path(dir) / tensor_file).string();
  if (!fs::is_regular_file(tensor_path, ec)) {
    throw InputError(tensor_path, 0, std::string("missing; the checkpoint is incomplete, ") + kTrainHint);
  }
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(tensor_path, torch::kCPU);
  } catch (const c10::Error& error) {
    throw InputError(tensor_path, 0,
                     "cannot read the tensors (truncated or corrupt?): " + first_line(error.what()) + "; " + kTrainHint);
  }
  const auto expected = named_tensors(*loaded.model);
  std::vector<std::string> stored;
  try {
    stored = archive.keys();
  } catch (const c10::Error& error) {
    throw InputError(tensor_path, 0, "cannot list the tensors: " + first_line(error.what()));
  }
  if (stored.size() != expected.size()) {
    throw InputError(tensor_path, 0,
                     "holds " + std::to_string(stored.size()) + " tensors, but the architecture in config.json has " +
                         std::to_string(expected.size()) + "; config.json and the tensors do not belong together");
  }
  torch::NoGradGuard no_grad;
  for (const auto& [name, tensor] : expected) {
    at::Tensor value;
    bool found = false;
    try {
      found = archive.try_read(name, value);
    } catch (const c10::Error& error) {
      throw InputError(tensor_path, 0, "cannot read tensor '" + name + "': " + first_line(error.what()));
    }
    if (!found) {
      throw InputError(tensor_path, 0, "has no tensor '" + name +
                                           "' that the architecture in config.json needs; config.json and the tensors "
                                           "do not belong together");
    }
    if (value.sizes() != tensor.sizes() || value.scalar_type() != tensor.scalar_type()) {
      throw InputError(tensor_path, 0, "tensor '" + name + "' is " + shape_text(value.sizes()) + " " +
                                           std::string(c10::toString(value.scalar_type())) + ", config.json implies " +
                                           shape_text(tensor.sizes()) + " " + c10::toString(tensor.scalar_type()) +
                                           "; config.json and the tensors do not belong together");
    }
    tensor.copy_(value);
  }
  return loaded;
}

}  // namespace nec::owo

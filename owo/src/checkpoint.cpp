// OwO checkpoint directories: config.json + tensors.pt, atomic save, checked load.
#include "nec/owo/checkpoint.h"

#include "nec/train/checkpoint_io.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <c10/util/Exception.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace nec::owo {
namespace {

namespace fs = std::filesystem;
using train::CheckpointConfig;
using train::JsonFields;
using train::read_checkpoint_config;
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

OwoConfig read_encoder_config(const JsonFields& reader, const json& root) {
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

PretrainConfig read_pretrain_config(const JsonFields& reader, const json& root) {
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

}  // namespace

void save_owo_checkpoint(const std::string& dir, OwoPretrainerImpl& model, const OwoCheckpointInfo& info) {
  train::write_checkpoint_directory(dir, "an OwO checkpoint", [&](const std::string& temp) {
    const json config = {{"format", kOwoCheckpointFormat},
                         {"version", kOwoCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"encoder", to_json(model.encoder->config())},
                         {"pretrain", to_json(model.config())},
                         {"training_step", info.training_step},
                         {"data", info.data},
                         {"tensors", kTensorFile}};
    write_file_atomic((fs::path(temp) / kConfigFile).string(), config.dump(2) + "\n");
    train::save_module_tensors(model, (fs::path(temp) / kTensorFile).string());
  });
}

LoadedOwoCheckpoint load_owo_checkpoint(const std::string& dir) {
  const CheckpointConfig config = read_checkpoint_config(dir, kOwoCheckpointFormat, kOwoCheckpointVersion, "an OwO checkpoint", kTrainHint);
  const JsonFields reader = config.fields();
  const json& root = config.root;
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
  train::load_module_tensors(*loaded.model, (fs::path(dir) / tensor_file).string(), kTrainHint);
  return loaded;
}

}  // namespace nec::owo

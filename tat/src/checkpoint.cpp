// TAT checkpoint directories: config.json + tensors.pt + the OwO checkpoint (+ optimizer state).
#include "nec/tat/checkpoint.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/checkpoint.h"
#include "nec/train/checkpoint_io.h"

#include <torch/torch.h>

#include <filesystem>
#include <stdexcept>

namespace nec::tat {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kArchitecture = "Tokenizer";
constexpr const char* kConfigFile = "config.json";
constexpr const char* kTensorFile = "tensors.pt";
constexpr const char* kOwoDir = "owo";
constexpr const char* kTrainHint = "run `nec train tat` to make one";

json to_json(const QuantizerConfig& c) {
  return {{"layers", c.layers},
          {"codebook_size", c.codebook_size},
          {"code_dim", c.code_dim},
          {"ema_decay", c.ema_decay},
          {"commitment_weight", c.commitment_weight},
          {"dead_code_threshold", c.dead_code_threshold},
          {"quantize_dropout", c.quantize_dropout}};
}

}  // namespace

json to_json(const TatConfig& c) {
  return {{"kind", to_string(c.kind)},
          {"joint_embedding_dim", c.joint_embedding_dim},
          {"dim", c.dim},
          {"blocks", c.blocks},
          {"attention_layers", c.attention_layers},
          {"heads", c.heads},
          {"max_joints", c.max_joints},
          {"quantizer", to_json(c.quantizer)}};
}

TatConfig tat_config_from_json(const json& object, const std::string& file, const std::string& where) {
  const train::JsonFields fields(file, "fix the field or remove it to use the default");
  TatConfig c;
  // Every field is optional in a training config; present ones must have the right type.
  auto read = [&](const json& parent, const char* key, const std::string& prefix, auto& out) {
    if (parent.contains(key)) fields.read(parent, key, prefix, out);
  };
  if (object.contains("kind")) {
    std::string kind;
    fields.read(object, "kind", where, kind);
    try {
      c.kind = tokenizer_kind_from_string(kind);
    } catch (const std::invalid_argument& e) {
      fields.fail("field '" + where + "kind': " + e.what());
    }
  }
  read(object, "joint_embedding_dim", where, c.joint_embedding_dim);
  read(object, "dim", where, c.dim);
  read(object, "blocks", where, c.blocks);
  read(object, "attention_layers", where, c.attention_layers);
  read(object, "heads", where, c.heads);
  read(object, "max_joints", where, c.max_joints);
  if (object.contains("quantizer")) {
    const std::string q_where = where + "quantizer.";
    const json& q = fields.object(object, "quantizer", where);
    read(q, "layers", q_where, c.quantizer.layers);
    read(q, "codebook_size", q_where, c.quantizer.codebook_size);
    read(q, "code_dim", q_where, c.quantizer.code_dim);
    read(q, "ema_decay", q_where, c.quantizer.ema_decay);
    read(q, "commitment_weight", q_where, c.quantizer.commitment_weight);
    read(q, "dead_code_threshold", q_where, c.quantizer.dead_code_threshold);
    read(q, "quantize_dropout", q_where, c.quantizer.quantize_dropout);
  }
  return c;
}

void save_tat_checkpoint(const std::string& dir, TokenizerImpl& tokenizer, owo::OwoPretrainerImpl& owo,
                         const TatCheckpointInfo& info, const std::function<void(const std::string&)>& extra) {
  train::write_checkpoint_directory(dir, "a TAT checkpoint", [&](const std::string& temp) {
    const fs::path root(temp);
    owo::save_owo_checkpoint((root / kOwoDir).string(), owo, {info.training_step, info.data});
    train::save_module_tensors(tokenizer, (root / kTensorFile).string());
    if (extra) extra(temp);
    const json config = {{"format", kTatCheckpointFormat},
                         {"version", kTatCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"tokenizer", to_json(tokenizer.config())},
                         {"window_frames", info.window_frames},
                         {"fps", info.fps},
                         {"training_step", info.training_step},
                         {"data", info.data},
                         {"tensors", kTensorFile},
                         {"owo", kOwoDir}};
    write_file_atomic((root / kConfigFile).string(), config.dump(2) + "\n");
  });
}

LoadedTatCheckpoint load_tat_checkpoint(const std::string& dir) {
  const train::CheckpointConfig config =
      train::read_checkpoint_config(dir, kTatCheckpointFormat, kTatCheckpointVersion, "a TAT checkpoint", kTrainHint);
  const train::JsonFields fields = config.fields();
  const json& root = config.root;
  std::string architecture;
  fields.read(root, "architecture", "", architecture);
  if (architecture != kArchitecture) fields.fail("architecture '" + architecture + "' is not " + kArchitecture);
  if (!root.contains("tokenizer")) fields.fail("field 'tokenizer' is missing; " + fields.hint());
  const TatConfig tokenizer_config = tat_config_from_json(fields.object(root, "tokenizer", ""), config.path, "tokenizer.");
  LoadedTatCheckpoint loaded;
  fields.read(root, "window_frames", "", loaded.info.window_frames);
  fields.read(root, "fps", "", loaded.info.fps);
  fields.read(root, "training_step", "", loaded.info.training_step);
  fields.read(root, "data", "", loaded.info.data);
  std::string tensor_file, owo_dir;
  fields.read(root, "tensors", "", tensor_file);
  fields.read(root, "owo", "", owo_dir);
  for (const std::string* name : {&tensor_file, &owo_dir}) {
    if (name->empty() || fs::path(*name).has_parent_path()) {
      fields.fail("fields 'tensors' and 'owo' must name entries inside the checkpoint directory");
    }
  }
  if (loaded.info.window_frames <= 0 || loaded.info.fps <= 0) {
    fields.fail("window_frames and fps must be positive; " + fields.hint());
  }
  try {
    tokenizer_config.validate();
    loaded.tokenizer = Tokenizer(tokenizer_config);
  } catch (const std::invalid_argument& error) {
    fields.fail(std::string(error.what()) + "; " + fields.hint());
  }
  train::load_module_tensors(*loaded.tokenizer, (fs::path(dir) / tensor_file).string(), kTrainHint);
  loaded.owo = owo::load_owo_checkpoint((fs::path(dir) / owo_dir).string()).model;
  if (tokenizer_config.kind != TokenizerKind::ZeroPadRvq &&
      loaded.owo->encoder->config().dim != tokenizer_config.joint_embedding_dim) {
    fields.fail("tokenizer.joint_embedding_dim is " + std::to_string(tokenizer_config.joint_embedding_dim) +
                " but the OwO encoder in '" + owo_dir + "' has dim " +
                std::to_string(loaded.owo->encoder->config().dim) + "; " + fields.hint());
  }
  loaded.tokenizer->eval();
  loaded.owo->eval();
  return loaded;
}

}  // namespace nec::tat

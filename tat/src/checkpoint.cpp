// TAT checkpoint directories: config.json + tensors.pt + the OwO checkpoint (+ optimizer state).
#include "nec/tat/checkpoint.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/checkpoint.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"

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

}  // namespace

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
                         {"tokenizer", train::write_config(tokenizer.config())},
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
  const TatConfig tokenizer_config =
      train::read_config_object<TatConfig>(root, "tokenizer", {config.path, fields.hint(), "", true});
  LoadedTatCheckpoint loaded;
  fields.read(root, "window_frames", "", loaded.info.window_frames);
  fields.read(root, "fps", "", loaded.info.fps);
  fields.read(root, "training_step", "", loaded.info.training_step);
  fields.read(root, "data", "", loaded.info.data);
  const std::string tensor_file = fields.entry(root, "tensors");
  const std::string owo_dir = fields.entry(root, "owo");
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

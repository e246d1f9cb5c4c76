// OwO checkpoint directories: config.json + tensors.pt, atomic save, checked load.
#include "nec/owo/checkpoint.h"

#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"

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

}  // namespace

void save_owo_checkpoint(const std::string& dir, OwoPretrainerImpl& model, const OwoCheckpointInfo& info) {
  train::write_checkpoint_directory(dir, "an OwO checkpoint", [&](const std::string& temp) {
    const json config = {{"format", kOwoCheckpointFormat},
                         {"version", kOwoCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"encoder", train::write_config(model.encoder->config())},
                         {"pretrain", train::write_config(model.config())},
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
  const train::ReadOptions fields{config.path, reader.hint(), "", true};
  const OwoConfig encoder_config = train::read_config_object<OwoConfig>(root, "encoder", fields);
  const PretrainConfig pretrain_config = train::read_config_object<PretrainConfig>(root, "pretrain", fields);
  LoadedOwoCheckpoint loaded;
  reader.read(root, "training_step", "", loaded.info.training_step);
  reader.read(root, "data", "", loaded.info.data);
  const std::string tensor_file = reader.entry(root, "tensors");
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

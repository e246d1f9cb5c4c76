// GPT checkpoint directories: write atomically, load with every check.
#include "nec/gpt/checkpoint.h"

#include "nec/motion/files.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"

#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <filesystem>
#include <stdexcept>

namespace nec::gpt {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kArchitecture = "TokenGpt";
constexpr const char* kTrainHint = "run `nec train gpt` to make one";

}  // namespace

void save_gpt_checkpoint(const std::string& dir, TokenGptImpl& model, const text::CaptionReader& captions,
                         tat::LoadedTatCheckpoint& tokenizer, const GptCheckpointInfo& info,
                         const std::function<void(const std::string&)>& extra) {
  train::write_checkpoint_directory(dir, "a GPT checkpoint", [&](const std::string& temp) {
    const fs::path root(temp);
    tat::save_tat_checkpoint((root / "tat").string(), *tokenizer.tokenizer, *tokenizer.owo, tokenizer.info);
    train::save_module_tensors(model, (root / "tensors.pt").string());
    if (extra) extra(temp);
    json config = {{"format", kGptCheckpointFormat},
                         {"version", kGptCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"gpt", train::write_config(model.config())},
                         {"fps", info.fps},
                         {"downsampling", tokenizer.tokenizer->config().downsampling()},
                         {"training_step", info.training_step},
                         {"data", info.data},
                         {"tensors", "tensors.pt"},
                         {"tat", "tat"}};
    text::save_checkpoint_captions(temp, captions, config);
    write_file_atomic((root / "config.json").string(), config.dump(2) + "\n");
  });
}

LoadedGpt load_gpt_checkpoint(const std::string& dir) {
  const train::CheckpointConfig config =
      train::read_checkpoint_config(dir, kGptCheckpointFormat, kGptCheckpointVersion, "a GPT checkpoint", kTrainHint);
  const train::JsonFields fields = config.fields();
  const json& root = config.root;
  std::string architecture;
  fields.read(root, "architecture", "", architecture);
  if (architecture != kArchitecture) fields.fail("architecture '" + architecture + "' is not " + kArchitecture);
  const GptConfig model_config = train::read_config_object<GptConfig>(root, "gpt", {config.path, fields.hint(), "", true});
  LoadedGpt loaded;
  fields.read(root, "fps", "", loaded.info.fps);
  fields.read(root, "training_step", "", loaded.info.training_step);
  fields.read(root, "data", "", loaded.info.data);
  int64_t downsampling = 0;
  fields.read(root, "downsampling", "", downsampling);
  const std::string tensor_file = fields.entry(root, "tensors");
  loaded.tat_dir = (fs::path(dir) / fields.entry(root, "tat")).string();
  try {
    loaded.model = TokenGpt(model_config);
  } catch (const std::invalid_argument& error) {
    fields.fail(std::string(error.what()) + "; " + fields.hint());
  }
  train::load_module_tensors(*loaded.model, (fs::path(dir) / tensor_file).string(), kTrainHint);
  loaded.captions = text::load_checkpoint_captions(dir, root, model_config.text, fields);
  // The tokenizer inside must be the one whose codes the GPT predicts.
  const train::CheckpointConfig tat_config = train::read_checkpoint_config(
      loaded.tat_dir, tat::kTatCheckpointFormat, tat::kTatCheckpointVersion, "the GPT's tokenizer", kTrainHint);
  const tat::TatConfig tokenizer =
      train::read_config_object<tat::TatConfig>(tat_config.root, "tokenizer", {tat_config.path, fields.hint(), "", true});
  if (tokenizer.quantizer.layers != model_config.codebook_layers ||
      tokenizer.quantizer.codebook_size != model_config.codebook_size || tokenizer.downsampling() != downsampling) {
    fields.fail("the tokenizer in tat/ does not match the GPT's codebook (" + std::to_string(model_config.codebook_layers) +
                " x " + std::to_string(model_config.codebook_size) + "); " + fields.hint());
  }
  loaded.model->eval();
  return loaded;
}

}  // namespace nec::gpt

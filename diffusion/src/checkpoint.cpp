// Diffusion checkpoint directories.
#include "nec/diffusion/checkpoint.h"

#include "nec/motion/files.h"
#include "nec/owo/checkpoint.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"

#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <filesystem>

namespace nec::diffusion {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kArchitecture = "MotionDenoiser";
constexpr const char* kConfigFile = "config.json";
constexpr const char* kTensorFile = "tensors.pt";
constexpr const char* kOwoDir = "owo";
constexpr const char* kTrainHint = "run `nec train diffusion` to make one";

}  // namespace

const char* to_string(DiffusionStage stage) { return stage == DiffusionStage::kPose ? "pose" : "motion"; }

void save_diffusion_checkpoint(const std::string& dir, MotionDenoiserImpl& model, owo::OwoPretrainerImpl& owo,
                               const text::CaptionReader& captions, const DiffusionCheckpointInfo& info,
                               const std::function<void(const std::string&)>& extra) {
  train::write_checkpoint_directory(dir, "a diffusion checkpoint", [&](const std::string& temp) {
    const fs::path root(temp);
    owo::save_owo_checkpoint((root / kOwoDir).string(), owo, {info.training_step, info.data});
    train::save_module_tensors(model, (root / kTensorFile).string());
    if (extra) extra(temp);
    json config = {{"format", kDiffusionCheckpointFormat},
                         {"version", kDiffusionCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"denoiser", train::write_config(model.config())},
                         {"stage", to_string(info.stage)},
                         {"fps", info.fps},
                         {"training_step", info.training_step},
                         {"data", info.data},
                         {"tensors", kTensorFile},
                         {"owo", kOwoDir}};
    text::save_checkpoint_captions(temp, captions, config);
    write_file_atomic((root / kConfigFile).string(), config.dump(2) + "\n");
  });
}

LoadedDiffusion load_diffusion_checkpoint(const std::string& dir) {
  const train::CheckpointConfig config = train::read_checkpoint_config(
      dir, kDiffusionCheckpointFormat, kDiffusionCheckpointVersion, "a diffusion checkpoint", kTrainHint);
  const train::JsonFields fields = config.fields();
  const json& root = config.root;
  std::string architecture, stage;
  fields.read(root, "architecture", "", architecture);
  if (architecture != kArchitecture) fields.fail("architecture '" + architecture + "' is not " + kArchitecture);
  fields.read(root, "stage", "", stage);
  if (stage != "pose" && stage != "motion") fields.fail("stage '" + stage + "' is neither pose nor motion");
  const DenoiserConfig model_config =
      train::read_config_object<DenoiserConfig>(root, "denoiser", {config.path, fields.hint(), "", true});
  LoadedDiffusion loaded;
  loaded.info.stage = stage == "pose" ? DiffusionStage::kPose : DiffusionStage::kMotion;
  fields.read(root, "fps", "", loaded.info.fps);
  fields.read(root, "training_step", "", loaded.info.training_step);
  fields.read(root, "data", "", loaded.info.data);
  const std::string tensor_file = fields.entry(root, "tensors");
  const std::string owo_dir = fields.entry(root, "owo");
  try {
    loaded.model = MotionDenoiser(model_config);
  } catch (const std::invalid_argument& error) {
    fields.fail(std::string(error.what()) + "; " + fields.hint());
  }
  train::load_module_tensors(*loaded.model, (fs::path(dir) / tensor_file).string(), kTrainHint);
  loaded.captions = text::load_checkpoint_captions(dir, root, model_config.text, fields);
  loaded.owo = owo::load_owo_checkpoint((fs::path(dir) / owo_dir).string()).model;
  if (model_config.joint_identity != JointIdentity::kTree &&
      loaded.owo->encoder->config().dim != model_config.skeleton_dim) {
    fields.fail("skeleton_dim is " + std::to_string(model_config.skeleton_dim) + " but the OwO encoder has dim " +
                std::to_string(loaded.owo->encoder->config().dim) + "; " + fields.hint());
  }
  loaded.model->eval();
  loaded.owo->eval();
  return loaded;
}

}  // namespace nec::diffusion

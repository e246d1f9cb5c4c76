// nec train diffusion: the generalized motion diffusion model, in two stages (pose, then motion).
#include "command_line.h"
#include "commands.h"
#include "training_command.h"

#include "nec/diffusion/training.h"
#include "nec/motion/error.h"
#include "nec/train/config_fields.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <optional>

namespace nec::app {

int run_train_diffusion(int argc, char** argv) {
  CommandLine cli("nec train diffusion",
                  "Train the diffusion model (How to Move Your Dragon) on the frozen OwO joint embeddings, in two\n"
                  "stages: --stage pose trains the pose model (spatial attention over the joints of single frames,\n"
                  "with the caption encoder); --stage motion freezes it and trains temporal attention blocks on\n"
                  "crops of motion. Rig augmentation on the fly; validates the denoising loss on the val split;\n"
                  "--resume continues from the checkpoint in --out; --nproc N trains data-parallel.\n"
                  "`nec generate --model OUT` uses the motion stage.");
  cli.option("--stage", "STAGE", "", "pose or motion", true);
  cli.option("--config", "CFG.json", "", "training config (see configs/diffusion_pose_cpu.json, diffusion_motion_cpu.json)", true);
  cli.option("--data", "CACHE", "", "dataset cache (from `nec prepare`); clips without captions train the unconditioned model", true);
  cli.option("--owo", "OWO_CKPT", "", "pose stage: pretrained OwO checkpoint (from `nec train owo`)");
  cli.option("--pieces", "SPM", "", "pose stage: caption piece model (from `nec text train-tokenizer`) when model.text.backbone is \"pieces\"");
  cli.option("--pose", "POSE_CKPT", "", "motion stage: the pose-stage checkpoint it builds on");
  cli.option("--out", "CKPT", "", "checkpoint directory to write", true);
  cli.option("--steps", "N", "0", "the step training ends at, instead of the config's (0 = keep)");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  declare_training_options(cli);
  cli.epilogue("fields of --config (every one optional; the default after =; the motion stage takes\n"
               "model.* from the pose model and refuses a \"model\" object):\n" +
               train::describe_config(diffusion::DiffusionTrainConfig{}));
  cli.example("nec train diffusion --stage pose --config configs/diffusion_pose_cpu.json --data cache/ --owo runs/owo --out runs/diffusion-pose");
  cli.example("nec train diffusion --stage motion --config configs/diffusion_motion_cpu.json --data cache/ --pose runs/diffusion-pose --out runs/diffusion");
  if (!cli.parse(argc, argv)) return 0;
  const std::string stage_name = cli.value("--stage");
  if (stage_name != "pose" && stage_name != "motion") throw UsageError("--stage must be pose or motion, got '" + stage_name + "'");
  const diffusion::DiffusionStage stage =
      stage_name == "pose" ? diffusion::DiffusionStage::kPose : diffusion::DiffusionStage::kMotion;
  if (const std::optional<int> workers = run_workers_if_asked(cli, "diffusion", argc, argv)) return *workers;
  const std::string out_dir = cli.value("--out");

  const std::string config_path = cli.value("--config");
  diffusion::DiffusionTrainConfig config = diffusion::read_diffusion_train_config(config_path);
  if (stage == diffusion::DiffusionStage::kMotion && train::read_config_json(config_path).contains("model")) {
    throw InputError(config_path, 0, "the motion stage takes its model from the pose model (--pose): remove \"model\"");
  }
  apply_steps_option(cli, config.steps);
  TrainingRun run = start_training_run(cli, out_dir);
  const DatasetCache cache = read_cache(cli.value("--data"));

  if (!run.resume && stage == diffusion::DiffusionStage::kMotion && cli.value("--pose").empty()) {
    throw UsageError("--pose POSE_CKPT is required for the motion stage unless --resume");
  }
  if (!run.resume && stage == diffusion::DiffusionStage::kPose) {
    if (cli.value("--owo").empty()) throw UsageError("--owo OWO_CKPT is required for the pose stage unless --resume");
    check_caption_inputs(config.model.text, cli.value("--pieces"), config_path);
  }
  diffusion::DiffusionTrainingInputs inputs =
      diffusion::load_training_inputs(stage, config, run.resume ? out_dir : "", cli.value("--owo"), cli.value("--pieces"),
                                      cli.value("--pose"), cli.value("--glove"));
  if (stage == diffusion::DiffusionStage::kPose) validate_config(config, config_path);

  std::optional<diffusion::DiffusionTrainer> trainer;
  try {
    trainer.emplace(config, stage, cache, cli.value("--data"), inputs.owo, std::move(inputs.pose), inputs.captions,
                    inputs.vectors ? &*inputs.vectors : nullptr, run.device, run.ranks.get());
  } catch (const std::invalid_argument& e) {
    throw InputError(config_path, 0, e.what());
  }
  const int64_t start_step = run.resume ? trainer->resume(out_dir) : 0;
  if (run.is_main()) {
    fmt::print("training the diffusion model's {} stage ({} trained parameters, joint identity {}) on {} ({} train "
               "clips); steps {}-{} of {} x {} frames on {}, {} process(es) x {} threads\n",
               stage_name, trainer->trained_parameter_count(), diffusion::to_string(trainer->model()->config().joint_identity),
               cli.value("--data"), trainer->train_clip_count(), start_step + 1, config.steps, config.batch_size,
               stage == diffusion::DiffusionStage::kPose ? config.pose_frames : config.data.window_frames,
               run.device.str(), run.ranks ? run.ranks->world_size() : 1, torch::get_num_threads());
    if (!trainer->has_validation()) fmt::print("no val clips: no validation\n");
    std::fflush(stdout);
  }
  const int code = run_training_steps(run, trainer->loop_schedule(), start_step, out_dir, trainer->hooks(out_dir));
  if (code == 0 && run.is_main()) {
    if (stage == diffusion::DiffusionStage::kPose) {
      fmt::print("next: nec train diffusion --stage motion --config configs/diffusion_motion_cpu.json --data {} --pose {} "
                 "--out OUT\n", cli.value("--data"), out_dir);
    } else {
      fmt::print("generate: nec generate \"a caption\" --skeleton SKELETON.bvh --model {} -o out.bvh\n", out_dir);
    }
  }
  return code;
}

}  // namespace nec::app

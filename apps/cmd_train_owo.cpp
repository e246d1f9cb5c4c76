// nec train owo: pretrain the OwO skeleton encoder on the skeletons of dataset caches.
#include "command_line.h"
#include "commands.h"
#include "training_command.h"

#include "nec/motion/error.h"
#include "nec/owo/training.h"
#include "nec/train/config_fields.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <optional>

namespace nec::app {
int run_train_owo(int argc, char** argv) {
  CommandLine cli("nec train owo",
                  "Pretrain the OwO skeleton graph encoder (NECromancer appendix C.2-C.3) on every distinct skeleton\n"
                  "of the dataset caches, with rig augmentations drawn on the fly (rest pose from the skeleton's own\n"
                  "clips, bone lengths, joint removal and subdivision). Skeletons the config's data.held_out patterns\n"
                  "name (e.g. whole body plans: \"spider\", \"snake\"), and what the caches hold out, are never trained\n"
                  "on: they validate every validate_every steps (LCA accuracy over all pairs, offset error, share of\n"
                  "trees rebuilt from the exact predicted LCA matrix: rebuilt, and from the predicted LCA\n"
                  "probabilities: decoded). A checkpoint (model + training state) is written every\n"
                  "checkpoint_every steps and at the end; --resume continues it with the same config.\n"
                  "A NaN or infinite loss stops training with exit code 1; the last checkpoint stays.\n"
                  "--nproc N trains data-parallel in N processes (docs/training.md: several machines).");
  cli.option("--config", "CFG.json", "", "training config (configs/owo_cpu.json, configs/owo_gpu.json)", true);
  cli.option("--data", "CACHES", "", "dataset caches from `nec prepare`, comma-separated", true);
  cli.option("--out", "CKPT", "", "checkpoint directory (replaced atomically at every checkpoint)", true);
  cli.option("--steps", "N", "", "the step training ends at, instead of the config's steps");
  cli.option("--glove", "FILE", text::default_word_vectors_path(), "word vectors for joint names (`nec text import-glove`)");
  cli.flag("--no-names", "train without joint names (sets names false and encoder.name_dim 0)");
  declare_training_options(cli);
  cli.epilogue("fields of --config (every one optional; the default after =):\n" +
               train::describe_config(owo::OwoTrainingConfig{}));
  cli.example("nec train owo --config configs/owo_cpu.json --data cache/ --out runs/owo");
  cli.example("nec train owo --config configs/owo_cpu.json --data cache/ --out runs/owo --resume --steps 6000");
  cli.example("nec train owo --config configs/owo_cpu.json --data cache/ --out runs/owo --nproc 2");
  if (!cli.parse(argc, argv)) return 0;
  if (const std::optional<int> workers = run_workers_if_asked(cli, "owo", argc, argv)) return *workers;

  const std::string config_path = cli.value("--config");
  const std::string out = cli.value("--out");
  const std::vector<std::string> caches = cli.list("--data");
  if (caches.empty()) throw UsageError("--data needs at least one cache");

  owo::OwoTrainingConfig config = owo::read_owo_training_config(config_path);
  if (!cli.value("--steps").empty()) {
    const int steps = cli.integer("--steps");
    if (steps < 1) throw UsageError("--steps must be >= 1");
    config.steps = steps;
  }
  if (cli.is_set("--no-names")) {
    config.names = false;
    config.encoder.name_dim = 0;
  }
  TrainingRun run = start_training_run(cli, out);

  std::optional<text::WordVectors> vectors;
  if (config.names) {
    try {
      vectors.emplace(text::WordVectors::load_checked(cli.value("--glove"), config.encoder.name_dim));
    } catch (const InputError& e) {
      throw InputError(std::string(e.what()) + " (" + config_path +
                       ": field 'encoder.name_dim'); or train without joint names: --no-names");
    }
  }

  std::vector<std::string> data;
  for (const std::string& cache : caches) data.push_back(std::filesystem::absolute(cache).lexically_normal().string());
  owo::SkeletonSet set = owo::load_skeleton_set(data, config.hold_out(), config.data.poses_per_skeleton, config.seed);
  if (set.train.empty()) {
    throw InputError(config_path, 0, "field 'data.held_out' holds out every skeleton of " + cli.value("--data") +
                                         "; nothing is left to train on");
  }
  owo::OwoTrainer trainer(config, std::move(set), vectors ? &*vectors : nullptr, run.device, run.ranks.get());
  const int64_t start_step = run.resume ? trainer.resume(out) : 0;

  if (run.is_main()) {
    const train::OptimizerConfig& o = config.optimizer;
    fmt::print("data     {}\n", trainer.describe_data(data));
    fmt::print("model    {} + pretraining heads, {} parameters; names {}\n", config.encoder.to_string(),
               trainer.parameter_count(), config.names ? vectors->path() : std::string("off"));
    fmt::print("run      steps {}-{}, batch {}, AdamW lr {:g} (warm-up {}, cosine to {:g}), clip {:g}; {}, {} "
               "process(es) x {} threads\n",
               start_step + 1, config.steps, config.batch_size, o.learning_rate, o.warmup_steps,
               o.learning_rate * o.final_lr_fraction, o.grad_clip, run.device.str(),
               run.ranks ? run.ranks->world_size() : 1, torch::get_num_threads());
    if (run.resume) fmt::print("resumed  {} at step {}\n", out, start_step);
  }
  const int code = run_training_steps(run, trainer.loop_schedule(), start_step, out, trainer.hooks(out, data));
  if (code == 0 && run.is_main()) fmt::print("evaluate: nec eval owo --model {} --data {}\n", out, cli.value("--data"));
  return code;
}

}  // namespace nec::app

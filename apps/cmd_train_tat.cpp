// nec train tat: train the tokenizer (or a baseline) on a dataset cache with a frozen OwO encoder.
#include "command_line.h"
#include "commands.h"
#include "training_command.h"

#include "nec/motion/error.h"
#include "nec/owo/checkpoint.h"
#include "nec/tat/checkpoint.h"
#include "nec/tat/training.h"
#include "nec/train/config_fields.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <filesystem>
#include <optional>

namespace nec::app {

int run_train_tat(int argc, char** argv) {
  CommandLine cli("nec train tat",
                  "Train the topology-agnostic tokenizer (or a baseline: model.kind nec-vq, zero-pad-rvq) on the\n"
                  "train split of a dataset cache, with the joint embeddings of a pretrained, frozen OwO encoder.\n"
                  "Shows progress, validates on the val split, writes a checkpoint every N steps and at the end;\n"
                  "--resume continues from the checkpoint in --out. Stops with a message on NaN/inf losses.\n"
                  "--nproc N trains data-parallel in N processes (docs/training.md: several machines).");
  cli.option("--config", "CFG.json", "", "training config (see configs/tat_cpu.json, configs/tat_gpu.json)", true);
  cli.option("--data", "CACHE", "", "dataset cache (from `nec prepare`)", true);
  cli.option("--owo", "OWO_CKPT", "", "pretrained OwO checkpoint (from `nec train owo`); not needed with --resume");
  cli.option("--out", "CKPT", "", "checkpoint directory to write", true);
  cli.option("--steps", "N", "0", "the step training ends at, instead of the config's (0 = keep)");
  cli.option("--kind", "KIND", "", "override model.kind: nec-rvq, nec-vq or zero-pad-rvq");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  declare_training_options(cli);
  cli.epilogue("fields of --config (every one optional; the default after =):\n" +
               train::describe_config(tat::TatTrainConfig{}));
  cli.example("nec train tat --config configs/tat_cpu.json --data cache/ --owo runs/owo --out runs/tat");
  cli.example("nec train tat --config configs/tat_cpu.json --data cache/ --out runs/tat --resume --steps 3000");
  cli.example("nec train tat --config configs/tat_cpu.json --data cache/ --owo runs/owo --out runs/tat --nproc 2");
  if (!cli.parse(argc, argv)) return 0;
  if (const std::optional<int> workers = run_workers_if_asked(cli, "tat", argc, argv)) return *workers;
  const std::string out_dir = cli.value("--out");

  tat::TatTrainConfig config = tat::read_tat_train_config(cli.value("--config"));
  apply_steps_option(cli, config.steps);
  if (!cli.value("--kind").empty()) {
    try {
      config.model.kind = tat::tokenizer_kind_from_string(cli.value("--kind"));
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--kind: ") + e.what());
    }
  }
  TrainingRun run = start_training_run(cli, out_dir);
  if (!run.resume && cli.value("--owo").empty()) throw UsageError("--owo OWO_CKPT is required unless --resume");
  const DatasetCache cache = read_cache(cli.value("--data"));
  // The frozen encoder: the one given, or the one the checkpoint being resumed was trained with.
  owo::OwoPretrainer owo = run.resume ? tat::load_tat_checkpoint(out_dir).owo : owo::load_owo_checkpoint(cli.value("--owo")).model;
  config.model.joint_embedding_dim = owo->encoder->config().dim;
  if (config.model.kind == tat::TokenizerKind::ZeroPadRvq && config.model.max_joints == 0) {
    config.model.max_joints = cache.max_joint_count();
  }
  if (config.model.kind == tat::TokenizerKind::NecVq) config.model.quantizer.layers = 1;
  validate_config(config, cli.value("--config"));
  std::optional<text::WordVectors> vectors;
  if (owo->encoder->config().name_dim > 0 && config.model.kind != tat::TokenizerKind::ZeroPadRvq) {
    vectors.emplace(text::WordVectors::load_checked(cli.value("--glove"), owo->encoder->config().name_dim));
  }

  tat::TatTrainer trainer(config, cache, cli.value("--data"), owo, vectors ? &*vectors : nullptr, run.device,
                          run.ranks.get());
  const int64_t start_step = run.resume ? trainer.resume(out_dir) : 0;
  if (run.is_main()) {
    fmt::print("training {} ({} parameters) on {} ({} train clips); steps {}-{} of {} x {} frames on {}, {} "
               "process(es) x {} threads\n",
               tat::to_string(config.model.kind), trainer.parameter_count(), cli.value("--data"),
               trainer.train_clip_count(), start_step + 1, config.steps, config.batch_size, config.data.window_frames,
               run.device.str(), run.ranks ? run.ranks->world_size() : 1, torch::get_num_threads());
    std::fflush(stdout);
  }

  const int code = run_training_steps(run, trainer.loop_schedule(), start_step, out_dir, trainer.hooks(out_dir));
  if (code == 0 && run.is_main()) fmt::print("evaluate: nec eval recon --model {} --data {}\n", out_dir, cli.value("--data"));
  return code;
}

}  // namespace nec::app

// nec train tat: train the tokenizer (or a baseline) on a dataset cache with a frozen OwO encoder.
#include "command_line.h"
#include "commands.h"
#include "torch_runtime.h"
#include "training_loop.h"

#include "nec/motion/error.h"
#include "nec/owo/checkpoint.h"
#include "nec/tat/checkpoint.h"
#include "nec/tat/training.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <thread>

namespace nec::app {
int run_train_tat(int argc, char** argv) {
  CommandLine cli("nec train tat",
                  "Train the topology-agnostic tokenizer (or a baseline: model.kind nec-vq, zero-pad-rvq) on the\n"
                  "train split of a dataset cache, with the joint embeddings of a pretrained, frozen OwO encoder.\n"
                  "Shows progress, validates on the val split, writes a checkpoint every N steps and at the end;\n"
                  "--resume continues from the checkpoint in --out. Stops with a message on NaN/inf losses.");
  cli.option("--config", "CFG.json", "", "training config (see configs/tat_cpu.json, configs/tat_gpu.json)", true);
  cli.option("--data", "CACHE", "", "dataset cache (from `nec prepare`)", true);
  cli.option("--owo", "OWO_CKPT", "", "pretrained OwO checkpoint (from `nec train owo`); not needed with --resume");
  cli.option("--out", "CKPT", "", "checkpoint directory to write", true);
  cli.option("--steps", "N", "0", "override the config's step count (0 = keep)");
  cli.option("--kind", "KIND", "", "override model.kind: nec-rvq, nec-vq or zero-pad-rvq");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.option("--threads", "N", "0", "torch threads; 0 = all cores");
  cli.option("--device", "DEVICE", "cpu", "cpu, cuda or cuda:N");
  cli.flag("--resume", "continue the run whose checkpoint is in --out (same config)");
  cli.example("nec train tat --config configs/tat_cpu.json --data cache/ --owo runs/owo --out runs/tat");
  cli.example("nec train tat --config configs/tat_cpu.json --data cache/ --out runs/tat --resume");
  if (!cli.parse(argc, argv)) return 0;
  use_torch_threads(threads_option(cli));
  const c10::Device device = device_option(cli);
  const std::string out_dir = cli.value("--out");
  const bool resume = cli.is_set("--resume");

  tat::TatTrainConfig config = tat::read_tat_train_config(cli.value("--config"));
  if (cli.integer("--steps") < 0) throw UsageError("--steps must be >= 0");
  if (cli.integer("--steps") > 0) config.steps = cli.integer("--steps");
  if (!cli.value("--kind").empty()) {
    try {
      config.model.kind = tat::tokenizer_kind_from_string(cli.value("--kind"));
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--kind: ") + e.what());
    }
    if (config.model.kind == tat::TokenizerKind::NecVq) config.model.quantizer.layers = 1;
  }
  const DatasetCache cache = read_cache(cli.value("--data"));

  // The model: fresh (with the OwO encoder) or from the checkpoint being resumed.
  std::optional<tat::LoadedTatCheckpoint> resumed;
  owo::OwoPretrainer owo{nullptr};
  if (resume) {
    resumed = tat::load_tat_checkpoint(out_dir);
    owo = resumed->owo;
  } else {
    if (cli.value("--owo").empty()) throw UsageError("--owo OWO_CKPT is required unless --resume");
    owo = owo::load_owo_checkpoint(cli.value("--owo")).model;
  }
  config.model.joint_embedding_dim = owo->encoder->config().dim;
  if (config.model.kind == tat::TokenizerKind::ZeroPadRvq && config.model.max_joints == 0) {
    config.model.max_joints = cache.max_joint_count();
  }
  if (config.model.kind == tat::TokenizerKind::NecVq) config.model.quantizer.layers = 1;
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(cli.value("--config"), 0, e.what());
  }
  tat::Tokenizer tokenizer{nullptr};
  if (resumed) {
    if (tat::to_json(resumed->tokenizer->config()) != tat::to_json(config.model)) {
      throw InputError(out_dir, 0,
                       "--resume: the checkpoint's model differs from --config's; use the config it was trained "
                       "with, or a new --out");
    }
    tokenizer = resumed->tokenizer;
  } else {
    torch::manual_seed(static_cast<uint64_t>(config.seed));  // the initial weights and codebooks
    tokenizer = tat::Tokenizer(config.model);
  }

  std::optional<text::WordVectors> vectors;
  if (owo->encoder->config().name_dim > 0 && config.model.kind != tat::TokenizerKind::ZeroPadRvq) {
    vectors.emplace(text::WordVectors::load(cli.value("--glove").empty() ? text::default_word_vectors_path()
                                                                        : cli.value("--glove")));
  }
  tat::TatTrainer trainer(tokenizer, owo, config, vectors ? &*vectors : nullptr, device);
  if (resumed && !resumed->optimizer_path.empty()) {
    torch::serialize::InputArchive archive;
    archive.load_from(resumed->optimizer_path, device);
    trainer.optimizer().load(archive);
  }

  BatchOptions batches;
  batches.batch_size = static_cast<int>(config.batch_size);
  batches.crop_frames = static_cast<int>(config.window_frames);
  batches.seed = config.seed;
  batches.drop_last = true;
  batches.augment_probability = config.augment_probability;
  batches.joint_buckets = static_cast<int>(config.joint_buckets);
  if (config.model.kind == tat::TokenizerKind::ZeroPadRvq) {
    // Subdivision adds joints beyond the fixed channel layout of the padding baseline.
    batches.augment_kinds = {AugmentKind::RestPose, AugmentKind::BoneLength, AugmentKind::JointRemoval};
  }
  BatchLoader train(cache, Split::Train, batches);
  if (train.batches_per_epoch() == 0) {
    throw InputError(cli.value("--data"), 0,
                     fmt::format("the train split has {} clips, fewer than one batch of {}", train.clip_count(),
                                 config.batch_size));
  }
  std::optional<BatchLoader> validation;
  BatchOptions validation_batches = batches;
  validation_batches.augment_probability = 0.0;
  validation_batches.joint_buckets = 0;
  validation_batches.shuffle = false;
  validation_batches.drop_last = false;
  if (!cache.clips_in(Split::Val).empty()) validation.emplace(cache, Split::Val, validation_batches);

  int64_t start_step = 0;
  if (resumed) {
    start_step = resumed->info.training_step;
    const nlohmann::json& state = resumed->info.training;
    train.seek(state.value("epoch", 0), state.value("index", 0));
  }
  const std::string data_text = fmt::format("{} ({} train clips)", cli.value("--data"), train.clip_count());
  fmt::print("training {} ({} parameters) on {}; {} steps of {} x {} frames on {}\n",
             tat::to_string(config.model.kind),
             [&] {
               int64_t n = 0;
               for (const auto& p : tokenizer->parameters()) n += p.numel();
               return n;
             }(),
             data_text, config.steps, config.batch_size, config.window_frames, device.str());
  std::fflush(stdout);

  TrainingSchedule schedule;
  schedule.total_steps = config.steps;
  schedule.log_every = config.log_every;
  schedule.validate_every = validation ? config.validate_every : 0;
  schedule.checkpoint_every = config.checkpoint_every;
  const InterruptSignals signals;
  TrainingHooks hooks;
  hooks.interrupted = [&] { return signals.received(); };
  hooks.step = [&](int64_t step) {
    const std::map<std::string, double> terms = trainer.step(train.next(), step - 1);
    LossTerms out;
    for (const char* key : {"loss", "rotation", "root", "position", "velocity", "commitment"}) {
      out.emplace_back(key, terms.at(key));
    }
    for (int64_t r = 0; r < config.model.quantizer.layers; ++r) {
      const std::string key = "perplexity" + std::to_string(r);
      if (terms.count(key)) out.emplace_back("ppl" + std::to_string(r), terms.at(key));
    }
    out.emplace_back("lr", terms.at("lr"));
    return out;
  };
  hooks.validate = [&](int64_t) {
    tat::ReconstructionMetrics metrics;
    const int count = std::min<int>(static_cast<int>(config.validation_batches), validation->batches_per_epoch());
    for (int i = 0; i < count; ++i) metrics.add(trainer.evaluate(validation->batch(0, i)));
    return LossTerms{{"val_mpjpe", metrics.mpjpe()},
                     {"val_mpjpe_no_trans", metrics.mpjpe_no_translation()},
                     {"val_geodesic_deg", metrics.geodesic_degrees()}};
  };
  hooks.checkpoint = [&](int64_t step) {
    tat::TatCheckpointInfo info;
    info.window_frames = config.window_frames;
    info.fps = cache.fps;
    info.training_step = step;
    info.data = data_text;
    info.training = {{"epoch", train.epoch()}, {"index", train.index()}, {"config", tat::to_json(config)}};
    tat::save_tat_checkpoint(out_dir, *trainer.tokenizer(), *trainer.owo(), info, &trainer.optimizer());
  };
  ProgressReporter progress(stdout, isatty(fileno(stdout)) != 0);
  const TrainingOutcome outcome = run_training(schedule, start_step, out_dir, hooks, progress);
  if (outcome.stopped || outcome.interrupted) {
    fmt::print(stderr, "nec: {}{}\n", outcome.stopped ? "error: " : "", outcome.message);
    return outcome.exit_code();
  }
  fmt::print("wrote {} (step {})\n", out_dir, outcome.last_step);
  return 0;
}

}  // namespace nec::app

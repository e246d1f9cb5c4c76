// nec train evaluator: the text-motion evaluator (motion + text encoders, contrastive) with a frozen OwO encoder.
#include "command_line.h"
#include "commands.h"
#include "training_command.h"

#include "nec/evaluator/training.h"
#include "nec/motion/error.h"
#include "nec/owo/checkpoint.h"
#include "nec/train/config_fields.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <filesystem>
#include <optional>

namespace nec::app {

int run_train_evaluator(int argc, char** argv) {
  CommandLine cli("nec train evaluator",
                  "Train the text-motion evaluator: a motion encoder for any skeleton (with the joint embeddings of a\n"
                  "pretrained, frozen OwO encoder) and the text encoder, contrastively on the (clip, caption) pairs\n"
                  "of the train split of a dataset cache, with rig augmentation. Validates R-Precision on the val\n"
                  "split and keeps the best model in OUT/best (what `nec retrieve` and `nec eval t2m` should read).\n"
                  "--resume continues from the checkpoint in --out; --nproc N trains data-parallel.");
  cli.option("--config", "CFG.json", "", "training config (see configs/evaluator_cpu.json)", true);
  cli.option("--data", "CACHE", "", "dataset cache with captions (from `nec prepare`)", true);
  cli.option("--owo", "OWO_CKPT", "", "pretrained OwO checkpoint (from `nec train owo`); not needed with --resume");
  cli.option("--pieces", "SPM", "", "caption piece model (from `nec text train-tokenizer`) when model.text.backbone is \"pieces\"; not needed with --resume");
  cli.option("--out", "CKPT", "", "checkpoint directory to write", true);
  cli.option("--steps", "N", "0", "the step training ends at, instead of the config's (0 = keep)");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  declare_training_options(cli);
  cli.epilogue("fields of --config (every one optional; the default after =):\n" +
               train::describe_config(evaluator::EvaluatorTrainConfig{}));
  cli.example("nec train evaluator --config configs/evaluator_cpu.json --data cache/ --owo runs/owo --out runs/eval");
  cli.example("nec train evaluator --config configs/evaluator_cpu.json --data cache/ --out runs/eval --resume --steps 4000");
  if (!cli.parse(argc, argv)) return 0;
  if (const std::optional<int> workers = run_workers_if_asked(cli, "evaluator", argc, argv)) return *workers;
  const std::string out_dir = cli.value("--out");

  evaluator::EvaluatorTrainConfig config = evaluator::read_evaluator_train_config(cli.value("--config"));
  apply_steps_option(cli, config.steps);
  TrainingRun run = start_training_run(cli, out_dir);
  if (!run.resume) {
    if (cli.value("--owo").empty()) throw UsageError("--owo OWO_CKPT is required unless --resume");
    check_caption_inputs(config.model.text, cli.value("--pieces"), cli.value("--config"));
  }
  const DatasetCache cache = read_cache(cli.value("--data"));
  // The frozen encoder and the piece model: the ones given, or those of the checkpoint being resumed.
  owo::OwoPretrainer owo{nullptr};
  std::string pieces_path = cli.value("--pieces");
  if (run.resume) {
    evaluator::LoadedEvaluator resumed = evaluator::load_evaluator_checkpoint(out_dir);
    owo = resumed.owo;
    pieces_path = resumed.captions.piece_model_path();  // read before the first save replaces the directory
  } else {
    owo = owo::load_owo_checkpoint(cli.value("--owo")).model;
  }
  text::CaptionReader captions = text::CaptionReader::for_training(config.model.text, pieces_path);
  config.model.motion.joint_embedding_dim = owo->encoder->config().dim;
  const int64_t name_dim = owo->encoder->config().name_dim;
  std::optional<text::WordVectors> vectors;
  if (config.model.text.word_dim > 0 || name_dim > 0) {
    vectors.emplace(text::WordVectors::load_checked(cli.value("--glove"), config.model.text.word_dim > 0
                                                                              ? config.model.text.word_dim
                                                                              : name_dim));
    if (name_dim > 0 && vectors->dim() != name_dim) {
      throw InputError(vectors->path(), 0,
                       "the OwO encoder reads names of width " + std::to_string(name_dim) + ", model.text.word_dim is " +
                           std::to_string(config.model.text.word_dim) + ": set it to " + std::to_string(name_dim));
    }
  }
  validate_config(config, cli.value("--config"));

  evaluator::EvaluatorTrainer trainer(config, cache, cli.value("--data"), owo, std::move(captions), vectors ? &*vectors : nullptr,
                                      run.device, run.ranks.get());
  const int64_t start_step = run.resume ? trainer.resume(out_dir) : 0;
  if (run.is_main()) {
    fmt::print("training the evaluator ({} parameters) on {} ({} captioned train clips); steps {}-{} of {} x {} frames "
               "on {}, {} process(es) x {} threads\n",
               trainer.parameter_count(), cli.value("--data"), trainer.train_clip_count(), start_step + 1, config.steps,
               config.batch_size, config.data.window_frames, run.device.str(), run.ranks ? run.ranks->world_size() : 1,
               torch::get_num_threads());
    if (config.captions.synonym_probability > 0) {
      fmt::print("caption synonyms: {} of the train captions' words have {} synonyms among the word vectors\n",
                 trainer.synonyms().word_count(), trainer.synonyms().synonym_count());
    }
    if (!trainer.has_validation()) {
      fmt::print("fewer than {} captioned val clips: no validation, no best model\n", evaluator::kMinValidationClips);
    }
    std::fflush(stdout);
  }
  const int code = run_training_steps(run, trainer.loop_schedule(), start_step, out_dir, trainer.hooks(out_dir));
  if (code == 0 && run.is_main() && trainer.best_step() > 0) {
    fmt::print("best: {}/best (val R@3 {:.3f} at step {})\n", out_dir, trainer.best_r_precision(), trainer.best_step());
  }
  return code;
}

}  // namespace nec::app

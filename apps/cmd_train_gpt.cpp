// nec train gpt: the text-to-token transformer on the tokens of a trained tokenizer.
#include "command_line.h"
#include "commands.h"
#include "training_command.h"

#include "nec/gpt/checkpoint.h"
#include "nec/gpt/training.h"
#include "nec/motion/error.h"
#include "nec/train/config_fields.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <filesystem>
#include <optional>

namespace nec::app {

int run_train_gpt(int argc, char** argv) {
  CommandLine cli("nec train gpt",
                  "Train the text-to-token transformer: it learns to write the token codes of a trained tokenizer\n"
                  "for a caption and a skeleton, on the captioned clips of the train split (their tokens are\n"
                  "computed once and stored beside the cache). Validates on the val split; --resume continues from\n"
                  "the checkpoint in --out; --nproc N trains data-parallel. `nec generate --model OUT` uses it.");
  cli.option("--config", "CFG.json", "", "training config (see configs/gpt_cpu.json)", true);
  cli.option("--data", "CACHE", "", "dataset cache with captions (from `nec prepare`)", true);
  cli.option("--tat", "TAT_CKPT", "", "tokenizer checkpoint (from `nec train tat`); not needed with --resume");
  cli.option("--pieces", "SPM", "", "caption piece model (from `nec text train-tokenizer`) when model.text.backbone is \"pieces\"; not needed with --resume");
  cli.option("--out", "CKPT", "", "checkpoint directory to write", true);
  cli.option("--steps", "N", "0", "the step training ends at, instead of the config's (0 = keep)");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  declare_training_options(cli);
  cli.epilogue("fields of --config (every one optional; the default after =):\n" + train::describe_config(gpt::GptTrainConfig{}));
  cli.example("nec train gpt --config configs/gpt_cpu.json --data cache/ --tat runs/tat --out runs/gpt");
  cli.example("nec train gpt --config configs/gpt_cpu.json --data cache/ --out runs/gpt --resume --steps 4000");
  if (!cli.parse(argc, argv)) return 0;
  if (const std::optional<int> workers = run_workers_if_asked(cli, "gpt", argc, argv)) return *workers;
  const std::string out_dir = cli.value("--out");

  gpt::GptTrainConfig config = gpt::read_gpt_train_config(cli.value("--config"));
  apply_steps_option(cli, config.steps);
  TrainingRun run = start_training_run(cli, out_dir);
  if (!run.resume) {
    if (cli.value("--tat").empty()) throw UsageError("--tat TAT_CKPT is required unless --resume");
    check_caption_inputs(config.model.text, cli.value("--pieces"), cli.value("--config"));
  }
  const DatasetCache cache = read_cache(cli.value("--data"));
  // The tokenizer and the piece model: the ones given, or those inside the checkpoint being resumed
  // (both read into memory by the trainer before its first save replaces --out).
  std::string tat_dir = cli.value("--tat"), pieces_path = cli.value("--pieces");
  if (run.resume) {
    const gpt::LoadedGpt resumed = gpt::load_gpt_checkpoint(out_dir);
    tat_dir = resumed.tat_dir;
    pieces_path = resumed.captions.piece_model_path();
  }
  tat::TokenizerSession tokenizer = tat::open_tokenizer_session(tat_dir, cli.value("--glove"), -1);
  const tat::TatConfig& tat = tokenizer.model.tokenizer->config();
  config.model.codebook_layers = tat.quantizer.layers;
  config.model.codebook_size = tat.quantizer.codebook_size;
  config.model.skeleton_dim = tokenizer.model.owo->encoder->config().dim;
  text::CaptionReader captions = text::CaptionReader::for_training(config.model.text, pieces_path);
  std::optional<text::WordVectors> vectors;
  if (config.model.text.word_dim > 0) {
    vectors.emplace(text::WordVectors::load_checked(cli.value("--glove"), config.model.text.word_dim));
  }
  validate_config(config, cli.value("--config"));

  gpt::GptTrainer trainer(config, cache, cli.value("--data"), tokenizer, tat_dir, std::move(captions),
                          vectors ? &*vectors : nullptr, run.device, run.ranks.get());
  const int64_t start_step = run.resume ? trainer.resume(out_dir) : 0;
  if (run.is_main()) {
    fmt::print("training the GPT ({} parameters) on {} ({} captioned train clips, {} x {} codes); steps {}-{} of {} "
               "items on {}, {} process(es) x {} threads\n",
               trainer.parameter_count(), cli.value("--data"), trainer.train_clip_count(), tat.quantizer.layers,
               tat.quantizer.codebook_size, start_step + 1, config.steps, config.batch_size, run.device.str(),
               run.ranks ? run.ranks->world_size() : 1, torch::get_num_threads());
    if (!trainer.has_validation()) fmt::print("no captioned val clips: no validation\n");
    std::fflush(stdout);
  }
  const int code = run_training_steps(run, trainer.loop_schedule(), start_step, out_dir, trainer.hooks(out_dir));
  if (code == 0 && run.is_main()) {
    fmt::print("generate: nec generate \"a caption\" --skeleton SKELETON.bvh --model {} -o out.bvh\n", out_dir);
  }
  return code;
}

}  // namespace nec::app

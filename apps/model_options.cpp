// Options shared by the commands that run a trained tokenizer.
#include "model_options.h"

#include "torch_runtime.h"

#include "nec/motion/error.h"
#include "nec/owo/stance.h"
#include "nec/text/word_vectors.h"

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace nec::app {

std::string default_model_dir(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(NEC_REPOSITORY_DIR) / "models" / "default" / name;
  return std::filesystem::exists(dir / "config.json") ? dir.string() : "";
}

std::string model_or_default(const std::string& given, const std::string& name, const std::string& option) {
  if (!given.empty()) return given;
  const std::string found = default_model_dir(name);
  if (found.empty()) {
    throw UsageError(option + " is needed: there are no default models in models/default (scripts/train_default_models.sh makes them)");
  }
  return found;
}

std::string checkpoint_format(const std::string& dir) {
  std::ifstream in(std::filesystem::path(dir) / "config.json");
  if (!in) return "";
  const nlohmann::json config = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
  if (!config.is_object() || !config.contains("format") || !config["format"].is_string()) return "";
  return config["format"].get<std::string>();
}

void declare_model_options(CommandLine& cli, bool with_model) {
  if (with_model) {
    cli.option("--model", "CKPT", "", "tokenizer checkpoint directory (from `nec train tat`); default: the\n"
                                             "default models' (models/default/gpt/tat)");
  }
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.option("--threads", "N", "0", "torch threads; 0 = all cores");
  cli.option("--window-overlap", "FRAMES", "auto",
             "frames shared by neighbouring windows of long clips (auto: a quarter of the model's window)");
}

TokenizerOptions tokenizer_options(const CommandLine& cli) {
  TokenizerOptions options;
  if (cli.declared("--model")) {
    options.model = model_or_default(cli.value("--model"), "gpt/tat", "--model");
  }
  options.glove = cli.value("--glove");
  options.threads = threads_option(cli);
  if (cli.value("--window-overlap") != "auto") {
    options.overlap_frames = cli.integer("--window-overlap");
    if (options.overlap_frames < 0) throw UsageError("--window-overlap must be >= 0 or auto");
  }
  return options;
}

std::shared_ptr<tat::TokenizerSession> open_tokenizer(const TokenizerOptions& options) {
  use_torch_threads(options.threads);
  try {
    return warm<tat::TokenizerSession>(
        WarmKind::Model,
        fmt::format("{}\n{}\noverlap {}", files_stamp(options.model), glove_stamp(options.glove), options.overlap_frames),
        [&] { return tat::open_tokenizer_session(options.model, options.glove, options.overlap_frames); });
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--window-overlap: ") + e.what());
  }
}

std::string glove_stamp(const std::string& glove) {
  return files_stamp(glove.empty() ? text::default_word_vectors_path() : glove);
}

void declare_stance_options(CommandLine& cli) {
  cli.option("--stance", "DIR", "", "stance network (`nec train stance`) that reads, from the skeleton file's first\n"
                                    "frame, the stance its creature's motion turns around; default: the default\n"
                                    "models' (models/default/stance)");
  cli.flag("--rest-from-motion", "turn the motion around the mean pose of the skeleton file's own motion instead\n"
                                 "(the old behaviour; the file's pose then shows in the result)");
}

Stance open_stance(const CommandLine& cli, const std::string& glove) {
  if (cli.is_set("--rest-from-motion")) {
    if (!cli.value("--stance").empty()) throw UsageError("--stance and --rest-from-motion exclude each other");
    return {};
  }
  const auto open = [&](const std::string& dir) {
    Stance stance;
    stance.key = files_stamp(dir) + "\n" + glove_stamp(glove);
    stance.network = warm<owo::NetworkStance>(WarmKind::Model, stance.key, [&] { return owo::NetworkStance::open(dir, glove); });
    return stance;
  };
  if (!cli.value("--stance").empty()) return open(cli.value("--stance"));
  const std::string dir = default_model_dir("stance");
  try {
    if (!dir.empty()) return open(dir);
    fmt::print(stderr, "note: no stance network in models/default/stance");
  } catch (const InputError& e) {  // e.g. the word vectors it reads joint names with are not installed
    fmt::print(stderr, "note: the default stance network cannot be used: {}", e.what());
  }
  fmt::print(stderr, "; the skeleton's rest is the mean pose of its motion\n");
  return {};
}

PreparedClip prepare_target(const std::string& path, double fps, UpAxis up, const Stance& stance) {
  const std::string key = fmt::format("{}\nfps {} up {}\nstance {}", files_stamp(path), fps, static_cast<int>(up), stance.key);
  PreparedClip target =
      *warm<PreparedClip>(WarmKind::Rig, key, [&] { return tat::prepare_target(path, fps, up, stance.network.get()); });
  for (const std::string& warning : target.report.warnings) fmt::print(stderr, "note: {}: {}\n", path, warning);
  return target;
}

}  // namespace nec::app

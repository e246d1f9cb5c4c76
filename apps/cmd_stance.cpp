// nec train stance / nec eval stance: the network that gives a rig without motion its creature's stance.
#include "command_line.h"
#include "commands.h"
#include "torch_runtime.h"

#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/stance.h"

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <optional>

namespace nec::app {
namespace {

std::vector<owo::StanceExample> examples_of(const std::vector<std::string>& caches,
                                            const owo::StanceExampleOptions& options) {
  std::vector<owo::StanceExample> out;
  for (const std::string& dir : caches) {
    std::vector<owo::StanceExample> some = owo::stance_examples(read_cache(dir), options);
    out.insert(out.end(), std::make_move_iterator(some.begin()), std::make_move_iterator(some.end()));
  }
  return out;
}

// --frames, --hold-out and --seed: which examples are drawn.
owo::StanceExampleOptions example_options(const CommandLine& cli) {
  owo::StanceExampleOptions options;
  options.frames_per_rig = cli.integer("--frames");
  options.held_out = cli.list("--hold-out");
  options.seed = static_cast<uint64_t>(cli.integer("--seed"));
  if (options.frames_per_rig < 0) throw UsageError("--frames must be >= 0");
  return options;
}

void print_scores(const std::vector<owo::StanceScore>& scores) {
  fmt::print("{:<30} {:>8} {:>6} {:>8} {:>8} {:>8} {:>16}\n", "group", "examples", "bones", "median", "mean", "p90",
             "median by length");
  for (const owo::StanceScore& s : scores) {
    fmt::print("{:<30} {:>8} {:>6} {:>7.1f}° {:>7.1f}° {:>7.1f}° {:>15.1f}°\n", s.group, s.examples, s.bones, s.median,
               s.mean, s.p90, s.weighted_median);
  }
}

}  // namespace

int run_train_stance(int argc, char** argv) {
  CommandLine cli("nec train stance",
                  "Train the stance network: a rig given without motion (one frame in any bind pose) -> where each\n"
                  "bone points in its creature's typical stance (the mean pose of all its clips, the canonical rest\n"
                  "the models learned motion around; docs/features.md#stance). Every rig of the caches is shown in\n"
                  "its file's own rest pose, in frames of its clips and in its stance with joints turned at random\n"
                  "(with --rest-turned, its rest pose so too).\n"
                  "Rigs the caches hold out, and those --hold-out patterns name, are not trained on: the held-out\n"
                  "errors (degrees between predicted and true bone directions) are printed and kept in the checkpoint.");
  cli.option("--data", "CACHES", "", "dataset caches from `nec prepare`, comma-separated", true);
  cli.option("--out", "DIR", "", "checkpoint directory (replaced atomically)", true);
  cli.option("--hold-out", "PATTERNS", "", "skeletons to keep out, comma-separated (as nec train owo's data.held_out)");
  cli.option("--steps", "N", "1200", "optimizer steps");
  cli.option("--batch", "N", "16", "examples per step");
  cli.option("--frames", "N", "12", "poses drawn from each rig's clips");
  cli.option("--glove", "FILE", "", "word vectors for joint names (with --names)");
  cli.flag("--names", "read joint names (needs the word vectors)");
  cli.option("--seed", "N", "1", "initialization, examples and batches");
  cli.option("--passes", "N", "1", "times the network reads the rig, each time as the last pass turned it\n"
                                  "(kept in the checkpoint: every command uses it)");
  cli.option("--rest-turned", "N", "0", "the file's rest pose with joints turned at random, per rig");
  cli.option("--length-jitter", "X", "0", "training rigs' bone lengths scaled by 1 +- X, each bone on its own");
  cli.option("--threads", "N", "1", "torch threads (0: every core; one is fastest for these small batches)");
  cli.example("nec train stance --data out/default-models/cache --out runs/stance --hold-out '*/bvh/13_*'");
  if (!cli.parse(argc, argv)) return 0;
  use_torch_threads(threads_option(cli));
  const std::string out = cli.value("--out");
  owo::StanceExampleOptions examples_drawn = example_options(cli);
  examples_drawn.length_jitter = cli.number("--length-jitter");
  examples_drawn.rest_turned_per_rig = cli.integer("--rest-turned");
  if (examples_drawn.length_jitter < 0.0 || examples_drawn.length_jitter >= 1.0) {
    throw UsageError("--length-jitter must be in [0, 1)");
  }
  if (examples_drawn.rest_turned_per_rig < 0) throw UsageError("--rest-turned must be >= 0");
  owo::StanceTrainingOptions options;
  options.steps = cli.integer("--steps");
  options.batch_size = cli.integer("--batch");
  options.seed = examples_drawn.seed;
  options.passes = cli.integer("--passes");
  if (options.steps < 1 || options.batch_size < 1) throw UsageError("--steps and --batch must be >= 1");
  if (options.passes < 1) throw UsageError("--passes must be >= 1");
  std::optional<text::WordVectors> vectors;
  if (cli.is_set("--names")) {
    const std::string glove = cli.value("--glove");
    vectors.emplace(text::WordVectors::load(glove.empty() ? text::default_word_vectors_path() : glove));
    options.name_dim = vectors->dim();
  }
  const std::vector<std::string> caches = cli.list("--data");
  const std::vector<owo::StanceExample> examples = examples_of(caches, examples_drawn);
  std::vector<owo::StanceExample> held_out;
  for (const owo::StanceExample& e : examples) {
    if (e.held_out) held_out.push_back(e);
  }
  fmt::print("data     {} examples of {} cache(s), {} held out\n", examples.size(), caches.size(), held_out.size());
  std::fflush(stdout);
  owo::StanceCheckpointInfo info;
  info.training_step = options.steps;
  info.passes = options.passes;
  for (const std::string& cache : caches) info.data += (info.data.empty() ? "" : ", ") + cache;
  info.data += fmt::format(": {} examples, {} held out", examples.size(), held_out.size());
  info.validation = nlohmann::json::array();
  const owo::NetworkStance stance(owo::train_stance(examples, options, vectors ? &*vectors : nullptr,
                                                    [](const std::string& line) {
                                                      fmt::print("{}\n", line);
                                                      std::fflush(stdout);  // progress shows in a log as it comes
                                                    }),
                                  info, std::move(vectors));
  if (!held_out.empty()) {
    const std::vector<owo::StanceScore> scores = owo::score_stance(stance, held_out, owo::by_dataset_and_pose);
    print_scores(scores);
    for (const owo::StanceScore& s : scores) info.validation.push_back(s.to_json());
  }
  owo::save_stance_checkpoint(out, stance.net(), info);
  fmt::print("wrote {}\n", out);
  return 0;
}

int run_eval_stance(int argc, char** argv) {
  CommandLine cli("nec eval stance",
                  "Score a stance network on the rigs of dataset caches: the angle between each bone's predicted\n"
                  "and true stance direction (the mean pose of the rig's clips), from the rig's file rest pose, from\n"
                  "frames of its clips and from its stance and its rest pose with joints turned at random; per\n"
                  "dataset and pose.");
  cli.option("--model", "DIR", "", "stance checkpoint (`nec train stance`)", true);
  cli.option("--data", "CACHES", "", "dataset caches from `nec prepare`, comma-separated", true);
  cli.option("--glove", "FILE", "", "word vectors, for a network that reads joint names");
  cli.option("--frames", "N", "12", "poses drawn from each rig's clips");
  cli.option("--seed", "N", "2", "which poses and turns");
  cli.option("--hold-out", "PATTERNS", "", "also score these skeletons (comma-separated, as nec train stance's)");
  cli.flag("--all", "score every rig, not only those the caches hold out");
  cli.option("--json", "FILE", "", "also write the scores as JSON");
  cli.option("--passes", "N", "", "times the network reads the rig (default: the checkpoint's)");
  cli.example("nec eval stance --model models/default/stance --data out/real-rigs/cache --all");
  if (!cli.parse(argc, argv)) return 0;
  owo::NetworkStance stance = owo::NetworkStance::open(cli.value("--model"), cli.value("--glove"));
  if (!cli.value("--passes").empty()) {
    if (cli.integer("--passes") < 1) throw UsageError("--passes must be >= 1");
    stance.set_passes(cli.integer("--passes"));
  }
  std::vector<owo::StanceExample> examples;
  for (owo::StanceExample& e : examples_of(cli.list("--data"), example_options(cli))) {
    if (cli.is_set("--all") || e.held_out) examples.push_back(std::move(e));
  }
  if (examples.empty()) throw InputError(cli.value("--data"), 0, "no held-out rig to score (--all scores every rig)");
  const auto group = owo::by_dataset_and_pose;
  const std::vector<owo::StanceScore> scores = owo::score_stance(stance, examples, group);
  print_scores(scores);
  // The same rigs with their bind pose kept as the stance (what they had before the network), for comparison.
  const std::vector<owo::StanceScore> kept = owo::score_stance(BindPoseStance(), examples, group);
  fmt::print("\nthe bind pose kept as the stance:\n");
  print_scores(kept);
  if (!cli.value("--json").empty()) {
    nlohmann::json all = nlohmann::json::array();
    for (const owo::StanceScore& s : scores) all.push_back(s.to_json());
    for (owo::StanceScore s : kept) {
      s.group += " (bind pose kept)";
      all.push_back(s.to_json());
    }
    write_file_atomic(cli.value("--json"), all.dump(2) + "\n");
  }
  return 0;
}

}  // namespace nec::app

// nec eval owo: a pretrained OwO encoder on skeletons it never trained on, and on its training skeletons.
#include "command_line.h"
#include "torch_runtime.h"
#include "commands.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/checkpoint.h"
#include "nec/owo/training.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <optional>
#include <thread>

namespace nec::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct Row {
  std::string label;  // e.g. "held out: spider"
  owo::ScoreSummary summary;
};

std::vector<owo::SkeletonScore> in_group(const std::vector<owo::SkeletonScore>& scores, const std::string& group) {
  std::vector<owo::SkeletonScore> out;
  for (const owo::SkeletonScore& s : scores) {
    if (s.group == group) out.push_back(s);
  }
  return out;
}

std::string joints_text(const owo::ScoreSummary& s) {
  if (s.skeletons == 0) return "-";
  return s.min_joints == s.max_joints ? std::to_string(s.min_joints) : fmt::format("{}-{}", s.min_joints, s.max_joints);
}

void print_table(const std::vector<Row>& rows, bool has_lca, bool has_offset) {
  fmt::print("\n| skeletons | count | joints | LCA accuracy (all pairs) | offset error | offset (% of diameter) | "
             "trees rebuilt from the exact LCA matrix | trees rebuilt from the LCA probabilities |\n"
             "|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    const owo::ScoreSummary& s = r.summary;
    const std::string lca = has_lca ? fmt::format("{:.4f}", s.lca_accuracy) : "-";
    const std::string offset = has_offset ? fmt::format("{:.4f}", s.offset_error) : "-";
    const std::string percent = has_offset ? fmt::format("{:.2f} %", s.offset_percent) : "-";
    auto share = [&](int count, double rate) {
      return has_lca ? fmt::format("{}/{} ({:.1f} %)", count, s.skeletons, 100.0 * rate) : std::string("-");
    };
    fmt::print("| {} | {} | {} | {} | {} | {} | {} | {} |\n", r.label, s.skeletons, joints_text(s), lca, offset, percent,
               share(s.rebuilt, s.rebuild_rate), share(s.decoded, s.decode_rate));
  }
}

json summary_json(const owo::ScoreSummary& s) {
  return {{"skeletons", s.skeletons},
          {"min_joints", s.min_joints},
          {"max_joints", s.max_joints},
          {"lca_accuracy", s.lca_accuracy},
          {"mean_lca_accuracy", s.mean_lca_accuracy},
          {"offset_error", s.offset_error},
          {"offset_percent_of_diameter", s.offset_percent},
          {"rebuilt", s.rebuilt},
          {"rebuild_rate", s.rebuild_rate},
          {"decoded", s.decoded},
          {"decode_rate", s.decode_rate}};
}

json scores_json(const std::vector<owo::SkeletonScore>& scores) {
  json out = json::array();
  for (const owo::SkeletonScore& s : scores) {
    out.push_back({{"name", s.name},
                   {"group", s.group},
                   {"joints", s.joints},
                   {"pairs", s.pairs},
                   {"lca_accuracy", s.lca_accuracy()},
                   {"rebuilt", s.rebuilt},
                   {"rebuild_failure", s.rebuild_failure},
                   {"decoded", s.decoded},
                   {"decoded_wrong_parents", s.decoded_wrong_parents},
                   {"offset_error", s.offset_error},
                   {"offset_percent_of_diameter", s.offset_percent}});
  }
  return out;
}

}  // namespace

int run_eval_owo(int argc, char** argv) {
  CommandLine cli("nec eval owo",
                  "Evaluate a pretrained OwO encoder (a checkpoint of `nec train owo`) on the skeletons of dataset\n"
                  "caches that it never trained on: those its run held out (whole body plans such as spider and\n"
                  "snake, and what the caches hold out) and any skeleton not among its training skeletons. Reports\n"
                  "the LCA pointer's accuracy over all joint pairs i < j, the rest-offset error (normalized units\n"
                  "and per cent of the skeleton's diameter), and the share of skeletons whose tree is rebuilt\n"
                  "(NECromancer appendix C.4) two ways: from the exact predicted LCA matrix (the argmax of every\n"
                  "pair; one wrong pair fails it), and from the predicted LCA probabilities (a tree decoded from\n"
                  "them: pair votes, a maximum spanning arborescence, then a likelihood climb); either counts only\n"
                  "when its parent array is the true one. The same on the training skeletons (un-augmented) for\n"
                  "contrast. Prints a Markdown table; --json writes every number.");
  cli.option("--model", "CKPT", "", "OwO checkpoint directory", true);
  cli.option("--data", "CACHES", "", "dataset caches, comma-separated", true);
  cli.option("--json", "OUT.json", "", "also write the results as JSON");
  cli.option("--hold-out", "PATTERNS", "",
             "skeletons to treat as held out (comma-separated patterns; default: the run's own data.held_out)");
  cli.option("--threads", "N", "0", "torch threads; 0 = all cores");
  cli.option("--device", "DEVICE", "cpu", "cpu, cuda or cuda:N");
  cli.option("--glove", "FILE", text::default_word_vectors_path(), "word vectors, when the model reads joint names");
  cli.flag("--no-names", "feed no joint names even when the model was trained with them");
  cli.example("nec eval owo --model runs/owo --data cache/ --json owo_eval.json");
  if (!cli.parse(argc, argv)) return 0;
  const std::string model_dir = cli.value("--model");
  const int threads = threads_option(cli);
  const c10::Device device = device_option(cli);
  const std::vector<std::string> caches = cli.list("--data");
  if (caches.empty()) throw UsageError("--data needs at least one cache");
  use_torch_threads(threads);
  const auto start = std::chrono::steady_clock::now();

  owo::LoadedOwoCheckpoint loaded = owo::load_owo_checkpoint(model_dir);
  loaded.model->to(device);
  const std::optional<owo::OwoTrainingRecord> record = owo::read_owo_training_record(model_dir);
  owo::HoldOut hold_out;
  if (!cli.value("--hold-out").empty()) {
    hold_out.patterns = cli.list("--hold-out");
  } else if (record) {
    hold_out = record->config.hold_out();
  } else {
    throw UsageError(model_dir + " has no training.json (not written by `nec train owo`): pass --hold-out PATTERNS "
                     "to name the skeletons it never saw");
  }
  const int64_t name_dim = loaded.model->encoder->config().name_dim;
  std::optional<text::WordVectors> vectors;
  if (name_dim > 0 && !cli.is_set("--no-names")) {
    try {
      vectors.emplace(text::WordVectors::load_checked(cli.value("--glove"), name_dim));
    } catch (const InputError& e) {
      throw InputError(std::string(e.what()) + "; or evaluate without joint names: --no-names");
    }
  }

  owo::SkeletonSet set = owo::load_skeleton_set(caches, hold_out, 0, 0);
  if (record) set = owo::split_as_trained(std::move(set), record->train_skeletons);
  std::vector<owo::PretrainSkeleton>& unseen = set.held_out;
  std::vector<owo::PretrainSkeleton>& seen = set.train;
  if (unseen.empty()) {
    throw InputError(cli.value("--data"), 0,
                     "holds no skeleton that " + model_dir + " did not train on; give caches with held-out skeletons");
  }

  const text::WordVectors* names = vectors ? &*vectors : nullptr;
  const std::vector<owo::SkeletonScore> unseen_scores = owo::score_skeletons(*loaded.model, unseen, names, device);
  const std::vector<owo::SkeletonScore> seen_scores = owo::score_skeletons(*loaded.model, seen, names, device);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::vector<std::string> groups;
  for (const owo::SkeletonScore& s : unseen_scores) {
    if (std::find(groups.begin(), groups.end(), s.group) == groups.end()) groups.push_back(s.group);
  }
  std::vector<Row> rows;
  for (const std::string& g : groups) rows.push_back({"held out: " + g, owo::summarize(in_group(unseen_scores, g))});
  const owo::ScoreSummary unseen_summary = owo::summarize(unseen_scores);
  const owo::ScoreSummary seen_summary = owo::summarize(seen_scores);
  if (groups.size() > 1) rows.push_back({"**held out: all**", unseen_summary});
  rows.push_back({"training skeletons", seen_summary});

  const bool has_lca = loaded.model->config().lca_loss, has_offset = loaded.model->config().offset_loss;
  fmt::print("model    {} (step {}): {}\n", model_dir, loaded.info.training_step, loaded.info.data);
  fmt::print("names    {}\n", names ? names->path() : std::string(name_dim > 0 ? "off (--no-names)" : "none (model reads no names)"));
  print_table(rows, has_lca, has_offset);
  int listed = 0;
  for (const owo::SkeletonScore& s : unseen_scores) {
    if (s.rebuilt || !has_lca) continue;
    if (listed++ == 0) fmt::print("\nheld-out trees not rebuilt from the exact LCA matrix:\n");
    if (listed > 12) continue;
    fmt::print("  {} ({}, {} joints, LCA accuracy {:.4f}): {}; from the probabilities: {}\n", s.name, s.group,
               s.joints, s.lca_accuracy(), s.rebuild_failure,
               s.decoded ? std::string("rebuilt") : fmt::format("{} wrong parents", s.decoded_wrong_parents));
  }
  if (listed > 12) fmt::print("  ... and {} more (all in --json)\n", listed - 12);
  fmt::print("\nscored {} held-out and {} training skeletons in {:.1f} s\n", unseen_scores.size(), seen_scores.size(),
             seconds);

  if (!cli.value("--json").empty()) {
    json groups_json = json::object();
    for (const std::string& g : groups) groups_json[g] = summary_json(owo::summarize(in_group(unseen_scores, g)));
    const json out = {{"model", model_dir},
                      {"training_step", loaded.info.training_step},
                      {"data", caches},
                      {"names", names != nullptr},
                      {"held_out",
                       {{"summary", summary_json(unseen_summary)},
                        {"groups", groups_json},
                        {"skeletons", scores_json(unseen_scores)}}},
                      {"train", {{"summary", summary_json(seen_summary)}, {"skeletons", scores_json(seen_scores)}}}};
    write_file_atomic(cli.value("--json"), out.dump(2) + "\n");
    fmt::print("wrote {}\n", cli.value("--json"));
  }
  return 0;
}

}  // namespace nec::app

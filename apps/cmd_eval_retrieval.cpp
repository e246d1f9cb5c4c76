// nec eval retrieval: the evaluator's text-motion R-Precision on a split of a cache, four ways.
#include "command_line.h"
#include "commands.h"

#include "nec/evaluator/retrieval.h"
#include "nec/motion/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <fmt/format.h>

#include <chrono>

namespace nec::app {

int run_eval_retrieval(int argc, char** argv) {
  CommandLine cli("nec eval retrieval",
                  "R-Precision of a trained evaluator on the captioned clips of one split of a cache, per dataset and\n"
                  "for all of them: mixed batches, batches within one body plan, the captions' creature words masked,\n"
                  "and the floor (captions shuffled). Batches of 32 (a smaller dataset: its size), 20 repeats, 95%\n"
                  "intervals. Each clip is read with its first caption, whole or its middle 256 frames.");
  cli.option("--data", "CACHE", "", "dataset cache with captions (from `nec prepare`)", true);
  cli.option("--evaluator", "EVAL", "", "evaluator checkpoint (from `nec train evaluator`, e.g. runs/eval/best)", true);
  cli.option("--split", "SPLIT", "test", "train, val or test");
  cli.option("--repeats", "N", "20", "reshuffles into batches");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.option("--json", "OUT.json", "", "also write the table as JSON");
  cli.example("nec eval retrieval --data cache/ --evaluator runs/eval/best --json retrieval.json");
  if (!cli.parse(argc, argv)) return 0;
  const auto split = parse_split(cli.value("--split"));
  if (!split) throw UsageError("--split must be train, val or test, got '" + cli.value("--split") + "'");
  if (cli.integer("--repeats") < 1) throw UsageError("--repeats must be >= 1");
  const auto start = std::chrono::steady_clock::now();
  const DatasetCache cache = read_cache(cli.value("--data"));
  evaluator::EvaluatorSession session = evaluator::open_evaluator(cli.value("--evaluator"), cli.value("--glove"));
  const evaluator::RetrievalSet set = evaluator::retrieval_set(cache, *split);
  if (set.clips.size() < 2) {
    throw InputError(cli.value("--data"), 0,
                     "has " + std::to_string(set.clips.size()) + " captioned clips in the " + cli.value("--split") +
                         " split; retrieval needs at least 2");
  }
  evaluator::RetrievalOptions options;
  options.repeats = static_cast<int>(cli.integer("--repeats"));
  evaluator::RetrievalTable table = evaluator::retrieval_table(session, cache, set, options);
  table.split = cli.value("--split");
  fmt::print("{}", evaluator::to_markdown(table));
  fmt::print("evaluator {} (step {}), {} of {}; {:.1f} s\n", cli.value("--evaluator"),
             session.loaded().info.training_step, cli.value("--split"), cli.value("--data"),
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!cli.value("--json").empty()) {
    nlohmann::json out = evaluator::to_json(table);
    out["data"] = cli.value("--data");
    out["evaluator"] = cli.value("--evaluator");
    write_file_atomic(cli.value("--json"), out.dump(2) + "\n");
  }
  return 0;
}

}  // namespace nec::app

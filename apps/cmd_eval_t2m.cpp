// nec eval t2m: generated motion (BVH + caption sidecars) judged with the evaluator against a cache's real motion.
#include "command_line.h"
#include "commands.h"

#include "nec/evaluator/t2m.h"
#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"

#include <fmt/format.h>

#include <chrono>

namespace nec::app {

int run_eval_t2m(int argc, char** argv) {
  CommandLine cli("nec eval t2m",
                  "Judge generated motion with a trained evaluator against the real motion of a cache split: for\n"
                  "each group (the first folder below --generated; its name picks the reference dataset) and for\n"
                  "all: R-Precision@1/2/3 and MM-Dist of the motions against their captions (mixed, and within\n"
                  "body plan: the plan from a zoo folder name cNNN_<plan>, else the group), FID and Diversity\n"
                  "against the real clips, Multimodality (captions with several samples), Coverage and Novelty AUC\n"
                  "(Dragon appendix C; windows against the real clips that carry the same caption), jitter and the\n"
                  "joints' turning per second (generated over real: the turning kept).\n"
                  "Each BVH needs its caption in a sidecar CLIP.txt.");
  cli.option("--generated", "DIR", "", "folder of generated BVH files with caption sidecars", true);
  cli.option("--reference", "CACHE", "", "dataset cache of real motion (from `nec prepare`)", true);
  cli.option("--evaluator", "EVAL", "", "evaluator checkpoint (from `nec train evaluator`, e.g. runs/eval/best)", true);
  cli.option("--split", "SPLIT", "test", "the reference split: train, val or test");
  cli.option("--batch", "N", "32", "R-Precision batch size (a smaller group: its size; within plan: plans under N skipped)");
  cli.option("--window-stride", "N", "5", "frames between Coverage / Novelty window starts (the paper: 1)");
  cli.flag("--across-creatures",
           "Coverage / Novelty against the real clips whose caption matches with creature words masked (novel\n"
           "compositions: 'a dragon leaps' against every other creature's leaps)");
  cli.option("--up", "AXIS", "auto", "up axis of the generated files: auto, y or z");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.option("--json", "OUT.json", "", "also write every number as JSON");
  cli.example("nec eval t2m --generated out/generated --reference cache/ --evaluator runs/eval/best --json t2m.json");
  if (!cli.parse(argc, argv)) return 0;
  const auto split = parse_split(cli.value("--split"));
  if (!split) throw UsageError("--split must be train, val or test, got '" + cli.value("--split") + "'");
  evaluator::T2mOptions options;
  options.window_stride = cli.integer("--window-stride");
  if (options.window_stride < 1) throw UsageError("--window-stride must be >= 1");
  options.batch_size = cli.integer("--batch");
  if (options.batch_size < 2) throw UsageError("--batch must be >= 2");
  options.coverage_across_creatures = cli.is_set("--across-creatures");
  const auto start = std::chrono::steady_clock::now();
  const DatasetCache cache = read_cache(cli.value("--reference"));
  evaluator::EvaluatorSession session = evaluator::open_evaluator(cli.value("--evaluator"), cli.value("--glove"));
  const std::vector<evaluator::GeneratedClip> generated =
      evaluator::read_generated(cli.value("--generated"), cache.fps, cli.up_axis("--up"));
  const evaluator::T2mReport report = evaluator::evaluate_t2m(session, generated, cache, *split, options);
  fmt::print("{}", evaluator::to_markdown(report));
  fmt::print("{} generated clips from {} against the {} split of {}; evaluator {}; {:.1f} s\n", generated.size(),
             cli.value("--generated"), cli.value("--split"), cli.value("--reference"), cli.value("--evaluator"),
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!cli.value("--json").empty()) {
    nlohmann::json out = evaluator::to_json(report);
    out["generated"] = cli.value("--generated");
    out["reference"] = cli.value("--reference");
    out["evaluator"] = cli.value("--evaluator");
    write_file_atomic(cli.value("--json"), out.dump(2) + "\n");
  }
  return 0;
}

}  // namespace nec::app

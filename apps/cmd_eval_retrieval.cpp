// nec eval retrieval: the evaluator's text-motion R-Precision on a split of a cache, four ways.
#include "command_line.h"
#include "commands.h"

#include "nec/evaluator/retrieval.h"
#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/tat/session.h"
#include "nec/text/caption_text.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <map>

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
  cli.option("--captions", "FILE.tsv", "",
             "only the clips listed (file name<TAB>caption), read with those captions and with their own, side by side\n"
             "(e.g. benchmarks/data/paraphrases.tsv)");
  cli.option("--tokenizer", "TAT", "", "also through this tokenizer: each clip encoded and decoded on its own skeleton");
  cli.option("--transfer", "SRC=DST,...", "",
             "with --tokenizer: clips of dataset SRC decoded onto the most used skeleton of dataset DST, read with\n"
             "their captions' creature words renamed to DST's (NECromancer Table 4), e.g. dog=bandai,bandai=dog");
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
  nlohmann::json out;
  if (cli.value("--captions").empty()) {
    const evaluator::RetrievalEmbeddings real = evaluator::embed_retrieval_set(session, cache, set);
    evaluator::RetrievalTable table = evaluator::retrieval_table(set, real, options);
    table.split = cli.value("--split");
    fmt::print("{}", evaluator::to_markdown(table));
    out = evaluator::to_json(table);
    if (!cli.value("--tokenizer").empty()) {
      tat::TokenizerSession tokenizer = tat::open_tokenizer_session(cli.value("--tokenizer"), cli.value("--glove"), -1);
      evaluator::RetrievalEmbeddings reconstructed = real;  // the same captions, the motions after the tokenizer
      reconstructed.motion = evaluator::to_embeddings(evaluator::embed_through_tokenizer(
          session, tokenizer, cache, set.clips, std::vector<int>(set.clips.size(), -1)));
      evaluator::RetrievalTable recon = evaluator::retrieval_table(set, reconstructed, options);
      recon.split = cli.value("--split") + ", reconstructed by " + cli.value("--tokenizer");
      fmt::print("\n{}", evaluator::to_markdown(recon));
      out = {{"real", out}, {"reconstructed", evaluator::to_json(recon)}};
      if (!cli.value("--transfer").empty()) {
        evaluator::RetrievalSet moved;
        std::vector<int> targets;
        for (const std::string& pair : cli.list("--transfer")) {
          const size_t eq = pair.find('=');
          if (eq == std::string::npos) throw UsageError("--transfer takes SRC=DST pairs, got '" + pair + "'");
          const std::string source = pair.substr(0, eq), target = pair.substr(eq + 1);
          std::map<int, int> uses;
          for (const CacheClip& clip : cache.clips) {
            if (clip.dataset == target) ++uses[clip.skeleton];
          }
          if (uses.empty()) throw InputError(cli.value("--data"), 0, "has no dataset '" + target + "' to transfer onto");
          const int skeleton = std::max_element(uses.begin(), uses.end(), [](const auto& a, const auto& b) {
                                 return a.second < b.second;
                               })->first;
          const std::string noun = evaluator::creature_noun_of(cache, target);
          for (size_t i = 0; i < set.clips.size(); ++i) {
            if (set.datasets[i] != source) continue;
            moved.clips.push_back(set.clips[i]);
            moved.captions.push_back(evaluator::mask_creature_words(text::normalize_caption(set.captions[i]), noun));
            moved.datasets.push_back(source + " -> " + target);
            moved.plans.push_back(set.plans[i]);
            targets.push_back(skeleton);
          }
        }
        if (moved.clips.size() < 2) throw UsageError("--transfer: fewer than 2 captioned clips to transfer");
        evaluator::RetrievalEmbeddings transferred = evaluator::embed_set_captions(session, moved);
        transferred.motion =
            evaluator::to_embeddings(evaluator::embed_through_tokenizer(session, tokenizer, cache, moved.clips, targets));
        evaluator::RetrievalTable transfer = evaluator::retrieval_table(moved, transferred, options);
        transfer.split = cli.value("--split") + ", transferred by " + cli.value("--tokenizer");
        fmt::print("\n{}", evaluator::to_markdown(transfer));
        out["transferred"] = evaluator::to_json(transfer);
      }
    }
  } else {
    const std::string file = cli.value("--captions");
    const evaluator::RetrievalSet given = evaluator::with_captions(set, cache, evaluator::read_file_captions(file), file);
    evaluator::RetrievalSet own = given;
    for (size_t i = 0; i < own.clips.size(); ++i) {
      own.captions[i] = cache.clips[static_cast<size_t>(own.clips[i])].captions.front();
    }
    const evaluator::RetrievalEmbeddings own_embeddings = evaluator::embed_retrieval_set(session, cache, own);
    evaluator::RetrievalEmbeddings given_embeddings = evaluator::embed_set_captions(session, given);
    given_embeddings.motion = own_embeddings.motion;  // the same clips
    evaluator::RetrievalTable own_table = evaluator::retrieval_table(own, own_embeddings, options);
    evaluator::RetrievalTable given_table = evaluator::retrieval_table(given, given_embeddings, options);
    own_table.split = cli.value("--split") + " (own captions)";
    given_table.split = cli.value("--split") + " (" + file + ")";
    fmt::print("{}\n{}", evaluator::to_markdown(own_table), evaluator::to_markdown(given_table));
    for (size_t r = 0; r < own_table.rows.size(); ++r) {
      const double own_r3 = own_table.rows[r].mixed.top_k.back().mean;
      const double given_r3 = given_table.rows[r].mixed.top_k.back().mean;
      fmt::print("{}: R@3 {:.3f} with {} against {:.3f} with their own captions ({:.0f} % kept)\n",
                 own_table.rows[r].name, given_r3, file, own_r3, own_r3 > 0 ? 100.0 * given_r3 / own_r3 : 0.0);
    }
    out = {{"own_captions", evaluator::to_json(own_table)}, {"given_captions", evaluator::to_json(given_table)},
           {"captions", file}};
  }
  fmt::print("evaluator {} (step {}), {} of {}; {:.1f} s\n", cli.value("--evaluator"),
             session.loaded().info.training_step, cli.value("--split"), cli.value("--data"),
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!cli.value("--json").empty()) {
    out["data"] = cli.value("--data");
    out["evaluator"] = cli.value("--evaluator");
    write_file_atomic(cli.value("--json"), out.dump(2) + "\n");
  }
  return 0;
}

}  // namespace nec::app

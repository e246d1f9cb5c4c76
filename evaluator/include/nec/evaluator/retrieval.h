// Text-motion retrieval over a dataset cache: how the evaluator's R-Precision
// is reported (NECromancer section 5; Guo et al. 2022), and the labels its
// shortcuts are measured with.
//
//   RetrievalSet set = retrieval_set(cache, Split::Test);          // clips with captions, their groups
//   RetrievalTable table = retrieval_table(set, embed_retrieval_set(session, cache, set), {});
//   std::cout << to_markdown(table);
//
// Shortcuts: captions name the creature and the skeleton gives it away, so a
// model that recognizes body plans scores well in mixed batches. The table
// therefore reports each dataset three ways besides the mixed number:
// batches within one body plan, the captions' creature words masked, and the
// floor (captions shuffled among the motions).
#pragma once

#include "nec/evaluator/evaluator.h"
#include "nec/evaluator/metrics.h"
#include "nec/corpus/dataset.h"
#include "nec/tat/session.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace nec::evaluator {

// The body plan of a file: the zoo's folder name `cNNN_<plan>` gives the
// plan ("quadruped", "spider"); any other file's plan is `dataset`.
std::string body_plan_of_file(const std::string& path, const std::string& dataset);
// body_plan_of_file of the clip's source and dataset.
std::string body_plan_of(const CacheClip& clip);

// The creature nouns captions use (the zoo's species and plans, "person", "someone", ...).
const std::vector<std::string>& creature_words();
// A normalized caption with every creature word (and its plural) replaced by
// `replacement`: "creature" masks them, a noun ("dog") renames the creature.
std::string mask_creature_words(const std::string& normalized_caption, const std::string& replacement = "creature");
// The creature word the captions of `dataset`'s clips use most ("" when none).
std::string creature_noun_of(const DatasetCache& cache, const std::string& dataset);

// The clips of one split that have captions, with their dataset and body plan.
struct RetrievalSet {
  std::vector<int> clips;             // indices into the cache
  std::vector<std::string> captions;  // each clip's first caption
  std::vector<std::string> datasets;  // each clip's dataset
  std::vector<std::string> plans;     // body_plan_of each clip
};
RetrievalSet retrieval_set(const DatasetCache& cache, Split split);

// Captions given by file: `file name<TAB>caption` per line, '#' comments and
// blank lines skipped (e.g. benchmarks/data/paraphrases.tsv). InputError naming
// the file and line for a line without a tab, an empty field or a file named twice.
std::vector<std::pair<std::string, std::string>> read_file_captions(const std::string& path);
// The clips of `set` whose source file name is listed, with the listed caption
// in place of their own (in list order; the first clip of a file when several
// share it). InputError naming `path` for a listed file not in the set.
RetrievalSet with_captions(const RetrievalSet& set, const DatasetCache& cache,
                           const std::vector<std::pair<std::string, std::string>>& captions, const std::string& path);

struct RetrievalOptions {
  int batch_size = 32;  // texts ranked against the motions of their batch (smaller groups: the group's size)
  int repeats = 20;     // reshuffles, e.g. 20
  uint64_t seed = 0;
};

// One row of the table: a dataset, or every dataset together ("all").
struct RetrievalRow {
  std::string name;       // dataset, or "all"
  int clips = 0;
  int batch_size = 0;     // the batch size used (chance R@k = k / batch_size)
  RPrecision mixed;       // batches over the row's clips, whatever their plan
  RPrecision within_plan; // batches inside one body plan (plans with fewer clips than the batch are skipped)
  bool has_within_plan = false;
  RPrecision masked;      // mixed batches, creature words of the captions masked
  RPrecision floor;       // mixed batches, captions shuffled among the motions (a new shuffle per repeat)
};

struct RetrievalTable {
  std::vector<RetrievalRow> rows;
  std::string split;
};

// The set's embeddings: its captions, the captions with creature words masked, and its clips.
struct RetrievalEmbeddings {
  Embeddings text, masked_text, motion;  // (N, D) each
};
RetrievalEmbeddings embed_retrieval_set(EvaluatorSession& session, const DatasetCache& cache, const RetrievalSet& set);
// The captions' part alone (motion left empty), for motions embedded another way.
RetrievalEmbeddings embed_set_captions(EvaluatorSession& session, const RetrievalSet& set);

// One row per dataset and one for all of them.
RetrievalTable retrieval_table(const RetrievalSet& set, const RetrievalEmbeddings& embeddings,
                               const RetrievalOptions& options);

// (N, D) embeddings of clips after a tokenizer: each clip (whole) encoded on its
// own skeleton and decoded onto skeleton `targets[i]` of the cache (-1: its own,
// a reconstruction), as `nec decode` does before writing BVH.
at::Tensor embed_through_tokenizer(EvaluatorSession& session, tat::TokenizerSession& tokenizer, const DatasetCache& cache,
                                   const std::vector<int>& clips, const std::vector<int>& targets);

std::string to_markdown(const RetrievalTable& table);
// {"r_precision": [{"mean", "half_width"}...], "mm_dist", "batches_per_repeat", "skipped_groups"}
nlohmann::json to_json(const RPrecision& r);
nlohmann::json to_json(const RetrievalTable& table);

}  // namespace nec::evaluator

// Text-motion retrieval over a dataset cache: how the evaluator's R-Precision
// is reported (NECromancer section 5; Guo et al. 2022), and the labels its
// shortcuts are measured with.
//
//   RetrievalSet set = retrieval_set(cache, Split::Test);          // clips with captions, their groups
//   RetrievalTable table = retrieval_table(session, cache, set, {});
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
#include "nec/motion/dataset.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace nec::evaluator {

// The body plan of a clip: the zoo's folder name `cNNN_<plan>` gives the
// plan ("quadruped", "spider"); any other clip's plan is its dataset.
std::string body_plan_of(const CacheClip& clip);

// The creature nouns captions use (the zoo's species and plans, "person", "someone", ...).
const std::vector<std::string>& creature_words();
// A normalized caption with every creature word (and its plural) replaced by "creature".
std::string mask_creature_words(const std::string& normalized_caption);

// The clips of one split that have captions, with their dataset and body plan.
struct RetrievalSet {
  std::vector<int> clips;             // indices into the cache
  std::vector<std::string> captions;  // each clip's first caption
  std::vector<std::string> datasets;  // each clip's dataset
  std::vector<std::string> plans;     // body_plan_of each clip
};
RetrievalSet retrieval_set(const DatasetCache& cache, Split split);

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
  RPrecision floor;       // mixed batches, captions shuffled among the motions
};

struct RetrievalTable {
  std::vector<RetrievalRow> rows;
  std::string split;
};

// Embeds the set once (motions, captions, masked captions) and fills one row
// per dataset and one for all of them.
RetrievalTable retrieval_table(EvaluatorSession& session, const DatasetCache& cache, const RetrievalSet& set,
                               const RetrievalOptions& options);
// The rows of `table` for given text and motion embeddings (what retrieval_table runs after embedding).
RetrievalTable retrieval_table(const RetrievalSet& set, const Embeddings& text, const Embeddings& masked_text,
                               const Embeddings& motion, const RetrievalOptions& options);

std::string to_markdown(const RetrievalTable& table);
nlohmann::json to_json(const RetrievalTable& table);

}  // namespace nec::evaluator

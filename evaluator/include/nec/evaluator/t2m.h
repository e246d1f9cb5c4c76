// Generated motion judged with the evaluator against real motion of a cache
// (Guo et al. 2022; NECromancer section 5; How to Move Your Dragon 6.1 and
// appendix C): what `nec eval t2m` prints, per group and for all.
//
//   std::vector<GeneratedClip> generated = read_generated("out/generated", cache.fps, UpAxis::Auto);
//   T2mReport report = evaluate_t2m(session, generated, cache, Split::Test, {});
//   std::cout << to_markdown(report);
//
// Generated clips are the BVH files below a folder, each with its caption in
// a sidecar `clip.txt` (what `nec generate` writes); several files with one
// caption are samples of it (Multimodality). A clip's group is the first
// folder below the root ("zoo/a.bvh" -> "zoo"), and is compared with the
// reference clips of the dataset of that name (all reference clips when no
// dataset has it). Files straight in the root belong to "all" only. A clip's
// body plan, for R-Precision within plan, is read from its folder as a cache
// clip's is (body_plan_of_file: "zoo/c003_spider/a.bvh" -> "spider"), else
// it is its group.
#pragma once

#include "nec/evaluator/evaluator.h"
#include "nec/evaluator/metrics.h"
#include "nec/corpus/dataset.h"
#include "nec/corpus/preprocess.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace nec::evaluator {

struct GeneratedClip {
  std::string path;
  std::string group;                  // first folder below the root, "" for files in the root
  std::string plan;                   // body_plan_of_file(path, group)
  std::vector<std::string> captions;  // from captions_for (sidecar); the first is the one judged
  PreparedClip prepared;              // preprocessed at the reference fps
};

// Every *.bvh below `dir` (sorted), preprocessed at `fps`. InputError naming
// the file for one that does not read, is rejected, or has no caption, and
// for a folder without BVH files.
std::vector<GeneratedClip> read_generated(const std::string& dir, double fps, UpAxis up);

struct T2mOptions {
  int batch_size = 32;           // R-Precision batches (a smaller group: its size)
  int repeats = 20;              // R-Precision reshuffles
  int diversity_pairs = 300;     // Guo et al.
  int multimodality_pairs = 10;  // per caption with at least 2 samples
  int max_window = 90;           // Coverage / Novelty window F (Dragon: 90 frames)
  int window_stride = 5;         // frames between window starts (Dragon: 1)
  // Coverage / Novelty against the reference clips whose caption is the same
  // once creature words are masked ("a dragon leaps" against every creature's
  // "a ... leaps"): novel compositions, an action the plan never did.
  bool coverage_across_creatures = false;
  uint64_t seed = 0;

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

// One group of generated clips against its reference clips. Values that a
// group cannot give (too few clips, no caption with two samples, no
// reference clip with the generated caption) are NaN.
struct T2mRow {
  std::string name;                 // the group, or "all"
  int generated = 0, reference = 0; // clips
  int batch_size = 0;               // R-Precision batch used (chance R@k = k / batch_size)
  RPrecision precision;             // generated motions against their captions
  bool has_precision = false;
  RPrecision within_plan;           // the same in batches of one body plan (plans under batch_size skipped)
  bool has_within_plan = false;
  double fid = 0;                   // generated vs reference embeddings
  double diversity = 0, reference_diversity = 0;
  double multimodality = 0;
  int multimodality_captions = 0;   // captions with at least 2 samples
  double coverage_auc = 0, novelty_auc = 0;  // mean over (generated, reference with the same caption) pairs
  int coverage_pairs = 0;
  double jitter = 0, reference_jitter = 0;   // skeleton diameters / s^3, mean over clips
  double turning = 0, reference_turning = 0; // the joints' turning, degrees / s (check_frame_rate), mean over clips
};

struct T2mReport {
  std::vector<T2mRow> rows;
  std::string split;
};

T2mReport evaluate_t2m(EvaluatorSession& session, const std::vector<GeneratedClip>& generated, const DatasetCache& cache,
                       Split split, const T2mOptions& options);

std::string to_markdown(const T2mReport& report);
nlohmann::json to_json(const T2mReport& report);

}  // namespace nec::evaluator

// nec prepare: folders of BVH files and rigged assets (+ captions) -> dataset cache.
#include "command_line.h"
#include "commands.h"

#include "nec/corpus/corpus.h"

#include <fmt/format.h>

#include <map>
#include <set>

namespace nec::app {
namespace {

double fraction_option(const CommandLine& cli, const std::string& name) {
  const double value = cli.number(name);
  if (value < 0.0 || value >= 1.0) throw UsageError(name + " must be in [0, 1)");
  return value;
}

}  // namespace

int run_prepare(int argc, char** argv) {
  CommandLine cli("nec prepare",
                  "Turn folders of BVH files and rigged assets (+ captions) into one dataset cache: every file\n"
                  "(every animation of an asset) is read, captioned, preprocessed (as nec normalize) and split into train/val/test by source file. Captions come\n"
                  "from clip.txt next to clip.bvh, --captions tables, or Bandai labels; takes without any are cut\n"
                  "into 2-6 s clips captioned from their kinematics (speed, turning, height, jumps).\n"
                  "Prints one line per file and a summary table.");
  cli.positional("INPUT", "folder (searched recursively) or file (BVH, FBX, glTF/GLB, Collada, .x); NAME=PATH names\n"
                          "its dataset", true, true);
  cli.option("-o", "CACHE", "", "output cache directory (replaced atomically)", true);
  cli.option("--fps", "FPS", "30", "corpus frame rate");
  cli.option("--source-fps", "FPS", "0", "the takes' true frame rate, replacing what every file says (BVH Frame Time),\n"
                                        "for files whose motion is implausible at their own rate (a warning says so);\n"
                                        "0: each file's own");
  cli.option("--up", "AXIS", "auto", "up axis of the inputs: auto, y or z");
  cli.option("--val", "FRACTION", "0.05", "fraction of source files for validation");
  cli.option("--test", "FRACTION", "0.05", "fraction of source files for test");
  cli.option("--seed", "N", "0", "split seed");
  cli.option("--hold-out", "PATTERNS", "", "skeleton names or hashes (comma-separated, * ? wildcards) put wholly in test");
  cli.option("--hold-out-dataset", "NAMES", "", "datasets (comma-separated) put wholly in test");
  cli.option("--captions", "CSV", "", "caption tables `file,caption` (comma-separated paths)");
  cli.option("--descriptions", "CSV", "",
             "take description tables `file,description` (comma-separated paths; more columns allowed\n"
             "when a header names them): described takes are still cut into clips, and each clip is\n"
             "captioned with the description's parts its kinematics agree with (travel: walks/runs a\n"
             "third of the clip; jump: a jump; sit/stand up: sits or lies; anything else: travels less\n"
             "than half), beside the kinematic caption");
  cli.flag("--no-kinematic-captions", "keep uncaptioned takes whole and without captions");
  cli.flag("--fold-translations", "fold every non-root joint's translation into its offset, even when it varies more\n"
                                   "than the jitter limits (1 % of the diameter, 10 % of the bone)");
  cli.option("--creature", "NOUN", "creature", "noun for segmenter captions; DATASET=NOUN pairs allowed, comma-separated");
  cli.option("--threads", "N", "0", "worker threads; 0 = all cores");
  cli.flag("--quiet", "print only the summary");
  cli.example("nec prepare bandai=../shared/data/bandai dog=../shared/data/mann_dog --creature dog=dog -o cache/");
  cli.example("nec prepare cmu=../shared/data/cmu/bvh --descriptions ../shared/data/cmu/descriptions.csv "
              "--creature cmu=person -o cache/");
  if (!cli.parse(argc, argv)) return 0;

  CorpusOptions corpus;
  corpus.preprocess.target_fps = cli.number("--fps");
  if (corpus.preprocess.target_fps <= 0) throw UsageError("--fps must be > 0");
  corpus.preprocess.up = cli.up_axis("--up");
  corpus.read.fps = cli.number("--source-fps");
  if (corpus.read.fps < 0) throw UsageError("--source-fps must be >= 0");
  corpus.preprocess.fold_any_translation = cli.is_set("--fold-translations");
  corpus.kinematic_captions = !cli.is_set("--no-kinematic-captions");
  corpus.threads = cli.integer("--threads");
  // Rows naming files that do not exist are most often a wrong folder: said once per table.
  const auto read_table = [](const std::string& csv) {
    CaptionTable table = CaptionTable::read(csv);
    if (const std::vector<std::string> missing = table.missing_files(); !missing.empty()) {
      fmt::print(stderr, "warning: {} names {} of its {} files that do not exist, e.g. {}\n", csv, missing.size(),
                 table.file_count(), missing.front());
    }
    return table;
  };
  for (const std::string& csv : cli.list("--captions")) corpus.captions.tables.push_back(read_table(csv));
  for (const std::string& csv : cli.list("--descriptions")) corpus.captions.descriptions.push_back(read_table(csv));
  std::string default_creature = "creature";
  std::map<std::string, std::string> creature_of;
  for (const std::string& item : cli.list("--creature")) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos) {
      default_creature = item;
    } else {
      creature_of[item.substr(0, eq)] = item.substr(eq + 1);
    }
  }
  CacheOptions cache_options;
  cache_options.preprocess = corpus.preprocess;
  cache_options.split.val_fraction = fraction_option(cli, "--val");
  cache_options.split.test_fraction = fraction_option(cli, "--test");
  cache_options.split.seed = static_cast<uint64_t>(cli.integer("--seed"));
  cache_options.split.held_out_skeletons = cli.list("--hold-out");
  cache_options.split.held_out_datasets = cli.list("--hold-out-dataset");
  try {
    cache_options.split.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }

  const std::vector<CorpusFile> files = find_corpus_files(cli.positionals("INPUT"));
  // Datasets are loaded one at a time so each gets its own creature noun.
  std::vector<std::string> order;
  std::map<std::string, std::vector<CorpusFile>> by_dataset;
  for (const CorpusFile& f : files) {
    if (!by_dataset.count(f.dataset)) order.push_back(f.dataset);
    by_dataset[f.dataset].push_back(f);
  }
  CorpusResult result;
  for (const std::string& dataset : order) {
    CorpusOptions options = corpus;
    const auto creature = creature_of.find(dataset);
    options.segment.creature = creature != creature_of.end() ? creature->second : default_creature;
    CorpusResult part = load_corpus(by_dataset[dataset], options);
    for (CacheEntry& e : part.entries) result.entries.push_back(std::move(e));
    for (CorpusFileResult& f : part.files) result.files.push_back(std::move(f));
  }
  const bool quiet = cli.is_set("--quiet");
  int rejected_files = 0;
  for (const CorpusFileResult& f : result.files) {
    if (!f.error.empty()) ++rejected_files;
    if (quiet && f.error.empty()) continue;
    std::string what;
    for (const std::string& change : f.changes) what += (what.empty() ? "" : "; ") + change;
    if (f.segments > 0) what += fmt::format("; cut into {} clips", f.segments);
    if (f.described > 0) what += "; captioned from its description";
    if (f.error.empty()) {
      fmt::print("ok       {}: {}\n", f.path, what);
    } else {
      fmt::print("rejected {}: {}\n", f.path, f.error);
    }
  }
  write_cache(cli.value("-o"), result.entries, cache_options);
  const DatasetCache cache = read_cache(cli.value("-o"));

  struct Row {
    std::set<int> skeletons;
    std::set<int> joint_counts;
    int clips = 0, frames = 0, captioned = 0;
    int split[3] = {0, 0, 0};
  };
  std::map<std::string, Row> rows;
  for (const CacheClip& c : cache.clips) {
    Row& r = rows[c.dataset];
    r.skeletons.insert(c.skeleton);
    r.joint_counts.insert(c.joint_count);
    ++r.clips;
    r.frames += c.frame_count;
    r.captioned += !c.captions.empty();
    ++r.split[static_cast<int>(c.split)];
  }
  fmt::print("\n| dataset | skeletons | joints | clips | frames | captioned | train/val/test |\n");
  fmt::print("|---|---|---|---|---|---|---|\n");
  for (const auto& [name, r] : rows) {
    const std::string joints = *r.joint_counts.begin() == *r.joint_counts.rbegin()
                                   ? std::to_string(*r.joint_counts.begin())
                                   : fmt::format("{}-{}", *r.joint_counts.begin(), *r.joint_counts.rbegin());
    fmt::print("| {} | {} | {} | {} | {} | {} | {}/{}/{} |\n", name, r.skeletons.size(), joints, r.clips, r.frames,
               r.captioned, r.split[0], r.split[1], r.split[2]);
  }
  fmt::print("\n{} files, {} rejected; {} clips at {:.4g} fps in {}\n", result.files.size(), rejected_files,
             cache.clips.size(), cache.fps, cli.value("-o"));
  return 0;
}

}  // namespace nec::app

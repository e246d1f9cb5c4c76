// nec demo: the whole pipeline on built-in data. Makes a small zoo, prepares it
// together with the real CMU files from Debian (and any --extra input), prints
// a table per body plan, and writes normalized and augmented BVH, PNG strips
// and viewer pages to look at.
#include "command_line.h"
#include "commands.h"

#include "nec/motion/augment.h"
#include "nec/motion/bvh.h"
#include "nec/motion/corpus.h"
#include "nec/motion/files.h"
#include "nec/viewer/html.h"
#include "nec/viewer/png.h"
#include "nec/viewer/strip.h"
#include "nec/zoo/zoo.h"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <set>

namespace nec::app {
namespace {

namespace fs = std::filesystem;

struct PlanRow {
  std::set<int> joint_counts;
  int clips = 0;
  int frames = 0;
};

std::string range_text(const std::set<int>& values) {
  if (values.empty()) return "-";
  if (*values.begin() == *values.rbegin()) return std::to_string(*values.begin());
  return fmt::format("{}-{}", *values.begin(), *values.rbegin());
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

int run_demo(int argc, char** argv) {
  CommandLine cli("nec demo",
                  "Run the pipeline on built-in data: make a small zoo of procedural creatures, prepare it with\n"
                  "the CMU motion capture files from Debian (and --extra inputs) into a dataset cache, print a\n"
                  "table per body plan, and write normalized and rig-augmented BVH, PNG strips and viewer pages.");
  cli.option("--out", "DIR", "out/demo", "output folder (its zoo/, cache/, bvh/, strips/ and *.html are replaced)");
  cli.option("--creatures", "N", "9", "zoo creatures (one per body plan for 9)");
  cli.option("--clips-per-creature", "M", "3", "zoo clips per creature");
  cli.option("--seed", "N", "0", "seed of the zoo, the splits and the augmentations");
  cli.option("--cmu", "DIR", "/usr/share/assimp/models/BVH", "CMU BVH folder (Debian assimp-testmodels); skipped if absent");
  cli.option("--extra", "INPUTS", "", "more inputs for the cache, comma-separated NAME=PATH (e.g. bandai=../shared/data/bandai)");
  cli.example("nec demo");
  cli.example("nec demo --extra bandai=../shared/data/bandai,dog=../shared/data/mann_dog");
  if (!cli.parse(argc, argv)) return 0;
  const auto start = std::chrono::steady_clock::now();
  const fs::path out = cli.value("--out");
  const int seed = cli.integer("--seed");
  for (const char* part : {"zoo", "cache", "bvh", "strips"}) {
    const std::string failure = remove_tree((out / part).string());
    if (!failure.empty()) throw std::runtime_error(failure);
  }
  fs::create_directories(out / "bvh");
  fs::create_directories(out / "strips");

  // 1. The zoo.
  zoo::ZooOptions zoo_options;
  zoo_options.out_dir = (out / "zoo").string();
  zoo_options.creatures = cli.integer("--creatures");
  zoo_options.clips_per_creature = cli.integer("--clips-per-creature");
  zoo_options.seed = static_cast<uint64_t>(seed);
  try {
    zoo_options.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  const zoo::ZooSummary zoo_summary = zoo::write_zoo(zoo_options);
  std::map<std::string, std::string> plan_of_file;  // BVH path -> body plan
  for (const zoo::ZooClip& c : zoo_summary.clips) {
    plan_of_file[(out / "zoo" / c.bvh_file).lexically_normal().string()] = std::string(zoo::body_plan_name(c.plan));
  }
  fmt::print("zoo: {} clips of {} creatures in {}\n", zoo_summary.clips.size(), zoo_summary.creatures,
             zoo_options.out_dir);

  // 2. The dataset cache: zoo + real data.
  std::vector<std::string> inputs = {"zoo=" + (out / "zoo").string()};
  const std::string cmu = cli.value("--cmu");
  if (fs::is_directory(cmu)) {
    inputs.push_back("cmu=" + cmu);
  } else {
    fmt::print("note: {} is missing (apt-get install assimp-testmodels); the demo uses the zoo only\n", cmu);
  }
  for (const std::string& input : cli.list("--extra")) inputs.push_back(input);
  CorpusOptions corpus_options;
  corpus_options.segment.creature = "person";  // the CMU takes, the only uncaptioned input
  CorpusResult corpus;
  for (const std::string& input : inputs) {
    CorpusOptions options = corpus_options;
    if (input.rfind("dog=", 0) == 0) options.segment.creature = "dog";
    CorpusResult part = load_corpus(find_corpus_files({input}), options);
    for (CacheEntry& e : part.entries) corpus.entries.push_back(std::move(e));
    for (CorpusFileResult& f : part.files) corpus.files.push_back(std::move(f));
  }
  CacheOptions cache_options;
  cache_options.preprocess = corpus_options.preprocess;
  cache_options.split.seed = static_cast<uint64_t>(seed);
  const std::string cache_dir = (out / "cache").string();
  write_cache(cache_dir, corpus.entries, cache_options);
  const DatasetCache cache = read_cache(cache_dir);
  for (const CorpusFileResult& f : corpus.files) {
    if (!f.error.empty()) fmt::print("rejected {}: {}\n", f.path, f.error);
  }

  // 3. The table, per body plan (zoo) or dataset (real data).
  std::map<std::string, PlanRow> rows;
  std::map<std::string, int> first_clip_of;  // row -> first cache clip
  for (int i = 0; i < cache.clip_count(); ++i) {
    const CacheClip& c = cache.clips[i];
    const auto plan = plan_of_file.find(fs::path(c.source).lexically_normal().string());
    const std::string row = plan != plan_of_file.end() ? plan->second : c.dataset + " (real)";
    PlanRow& r = rows[row];
    r.joint_counts.insert(c.joint_count);
    ++r.clips;
    r.frames += c.frame_count;
    first_clip_of.emplace(row, i);
  }
  fmt::print("\n| body plan | joints | clips | frames |\n|---|---|---|---|\n");
  for (const auto& [name, r] : rows) fmt::print("| {} | {} | {} | {} |\n", name, range_text(r.joint_counts), r.clips, r.frames);
  fmt::print("\ncache: {} clips at {:.4g} fps in {} ({} train / {} val / {} test)\n", cache.clip_count(), cache.fps,
             cache_dir, cache.clips_in(Split::Train).size(), cache.clips_in(Split::Val).size(),
             cache.clips_in(Split::Test).size());

  // 4. Normalized and augmented BVH, strips and pages.
  std::vector<viewer::ViewClip> normalized_views;
  std::vector<viewer::ViewClip> augmented_views;
  SplitMix64 rng(static_cast<uint64_t>(seed));
  for (const auto& [name, index] : first_clip_of) {
    const CacheClip& c = cache.clips[index];
    const Clip clip = cache.clip(index);
    const std::string stem = fs::path(c.source).stem().string();
    write_bvh((out / "bvh" / (stem + "_normalized.bvh")).string(), clip.skeleton, clip.motion);
    viewer::StripOptions strip_options;
    strip_options.frames = 5;
    strip_options.panel_height = 160;
    viewer::write_png((out / "strips" / (stem + ".png")).string(), viewer::render_strip(clip, strip_options));
    normalized_views.push_back({name, c.captions.empty() ? std::vector<std::string>{} : std::vector<std::string>{c.captions.front()}, clip});
    if (augmented_views.empty()) augmented_views.push_back({name + ": normalized", {}, clip});
    const std::vector<std::string>& canonical = cache.skeleton_of(index).canonical_names;
    for (const auto& [kind, label] : {std::pair{AugmentKind::RestPose, "rest"}, std::pair{AugmentKind::BoneLength, "length"},
                                      std::pair{AugmentKind::JointRemoval, "remove"},
                                      std::pair{AugmentKind::Subdivision, "subdivide"}}) {
      const Clip augmented = augment(clip, kind, canonical, rng);
      write_bvh((out / "bvh" / (stem + "_" + label + ".bvh")).string(), augmented.skeleton, augmented.motion);
      if (augmented_views.size() < 5 && index == first_clip_of.begin()->second) {
        augmented_views.push_back({name + ": " + label + fmt::format(" ({} joints)", augmented.skeleton.joint_count()),
                                   {},
                                   augmented});
      }
    }
  }
  std::vector<std::string> pages;
  if (viewer::have_three()) {
    viewer::ViewOptions page;
    page.title = "nec demo: one normalized clip per body plan";
    write_file_atomic((out / "index.html").string(), viewer::make_view_html(normalized_views, page));
    page.title = "nec demo: rig augmentations of one clip";
    write_file_atomic((out / "augmented.html").string(), viewer::make_view_html(augmented_views, page));
    pages = {(out / "index.html").string(), (out / "augmented.html").string()};
  } else {
    fmt::print("note: three.js was not built in (run scripts/setup.sh); no HTML pages written\n");
  }
  fmt::print("wrote {} BVH to {}, {} strips to {}", std::distance(fs::directory_iterator(out / "bvh"), fs::directory_iterator()),
             (out / "bvh").string(), normalized_views.size(), (out / "strips").string());
  for (const std::string& p : pages) fmt::print(", {}", p);
  fmt::print("\ndemo finished in {:.1f} s\n", seconds_since(start));
  return 0;
}

}  // namespace nec::app

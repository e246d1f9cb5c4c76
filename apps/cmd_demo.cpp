// nec demo: the whole pipeline on built-in data. Makes a small zoo, prepares it
// together with the real CMU files from Debian (and any --extra input), prints
// a table per body plan, and writes normalized and augmented BVH, PNG strips
// and viewer pages to look at.
#include "command_line.h"
#include "commands.h"
#include "model_options.h"

#include "nec/diffusion/generation.h"
#include "nec/evaluator/retrieval.h"
#include "nec/evaluator/retrieval_index.h"
#include "nec/gpt/generation.h"
#include "nec/owo/stance.h"
#include "nec/corpus/augment.h"
#include "nec/motion/bvh.h"
#include "nec/corpus/corpus.h"
#include "nec/motion/files.h"
#include "nec/viewer/html.h"
#include "nec/viewer/png.h"
#include "nec/viewer/strip.h"
#include "nec/zoo/zoo.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
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

// A player page of `clips` at `path` and a strip of the first of them beside it (same name, .png).
void write_page(const fs::path& path, const std::string& title, const std::vector<viewer::ViewClip>& clips) {
  viewer::ViewOptions page;
  page.title = title;
  write_file_atomic(path.string(), viewer::make_view_html(clips, page));
  viewer::StripOptions strip;
  strip.frames = 5;
  strip.panel_height = 160;
  viewer::write_png(fs::path(path).replace_extension(".png").string(), viewer::render_strip(clips.front().clip, strip));
}

// The three uses with the default models (models/default/): transfers between body plans, generation from each
// plan's own short caption (the hexapod is a plan the default models never saw) by the GPT and, for the first
// plans, by the diffusion model beside it, and text queries against the demo's cache. `clips_by_plan`: the first
// zoo clip of each plan with its short caption. Returns the pages written.
std::vector<std::pair<std::string, std::string>> run_model_demo(const fs::path& out,
                                                                const std::vector<std::pair<std::string, std::string>>& clips_by_plan,
                                                                const DatasetCache& cache) {
  const std::string gpt_dir = default_model_dir("gpt"), evaluator_dir = default_model_dir("evaluator");
  if (gpt_dir.empty() || evaluator_dir.empty() || !fs::exists(text::default_word_vectors_path())) {
    fmt::print("note: no default models in models/default (scripts/train_default_models.sh) or no word vectors "
               "(nec text import-glove): no transfers, generation or retrieval\n");
    return {};
  }
  const auto start = std::chrono::steady_clock::now();
  const fs::path models = out / "models";
  fs::create_directories(models);
  gpt::GeneratorSession session = gpt::open_generator(gpt_dir, "");
  const double fps = session.fps();
  std::vector<std::pair<std::string, std::string>> pages;
  // Skeletons that receive motion take their creature's stance, as in nec generate and nec transfer.
  const std::string stance_dir = default_model_dir("stance");
  std::optional<owo::NetworkStance> network_stance;
  if (!stance_dir.empty()) network_stance.emplace(owo::NetworkStance::open(stance_dir, ""));
  const StancePredictor* stance = network_stance ? &*network_stance : nullptr;

  // Transfers: the clip of each plan onto the skeleton of the next plan.
  std::vector<viewer::ViewClip> transfers;
  for (size_t i = 0; i + 1 < clips_by_plan.size() && transfers.size() < 10; ++i) {
    const auto& [source_path, caption] = clips_by_plan[i];
    const std::string& target_path = clips_by_plan[i + 1].first;
    const std::string result = (models / fmt::format("transfer_{}.bvh", i + 1)).string();
    const PreparedClip source = tat::prepare_for_model(source_path, fps, UpAxis::Auto);
    tat::DecodeCorrections corrections;
    corrections.source = &source.clip;
    tat::decode_onto(session.tokenizer, tat::encode_file(session.tokenizer, source, source_path), target_path, UpAxis::Auto,
                     stance, corrections, result);
    transfers.push_back(viewer::load_view_clip(source_path));
    transfers.back().captions = {caption};
    transfers.push_back(viewer::load_view_clip(result));
    transfers.back().name = "onto " + fs::path(target_path).stem().string();
  }
  if (!transfers.empty()) {
    write_page(models / "transfers.html", "nec demo: transfers between body plans (source, then result)", transfers);
    pages.emplace_back("Transfer: each clip onto the next body plan", "models/transfers");
  }

  // Generation: each plan's own short caption, 4 s, on its skeleton; the diffusion model's motion for the same
  // caption beside the GPT's for the first plans (a 4-s sample takes it seconds where the GPT takes a fraction).
  std::vector<viewer::ViewClip> generated;
  gpt::SamplingOptions sampling;
  const std::string diffusion_dir = default_model_dir("diffusion");
  std::optional<diffusion::DiffusionSession> diffusion_session;
  if (!diffusion_dir.empty()) diffusion_session.emplace(diffusion::open_diffusion(diffusion_dir, ""));
  int diffused = 0;
  for (size_t i = 0; i < clips_by_plan.size() && i < 5; ++i) {
    const auto& [skeleton_path, caption] = clips_by_plan[i];
    const PreparedClip target = tat::prepare_target(skeleton_path, fps, UpAxis::Auto, stance);
    const int64_t steps = static_cast<int64_t>(4.0 * fps) / session.downsampling();
    const at::Tensor codes = gpt::generate_codes(session, target, {{caption, steps}}, 1, sampling).front();
    const std::string result = (models / fmt::format("generated_{}.bvh", i + 1)).string();
    tat::decode_onto(session.tokenizer, session.token_file(codes, caption), target, skeleton_path, {}, result);
    generated.push_back(viewer::load_view_clip(result));
    generated.back().captions = {caption};
    if (diffusion_session && i < 3) {
      const PreparedClip on_skeleton =
          tat::prepare_target(skeleton_path, diffusion_session->fps(), UpAxis::Auto, stance);
      diffusion::DiffusionSamplingOptions options;  // generation's defaults
      options.seed = i;
      const Features motion = diffusion::generate_motions(*diffusion_session, on_skeleton,
                                                          {{caption, std::lround(4.0 * diffusion_session->fps())}}, 1, options)
                                  .front();
      const std::string diffused_path = (models / fmt::format("generated_{}_diffusion.bvh", i + 1)).string();
      tat::write_onto(on_skeleton, motion, {}, 0.0, skeleton_path, diffused_path, caption);
      generated.push_back(viewer::load_view_clip(diffused_path));
      generated.back().name += " (diffusion)";
      generated.back().captions = {caption};
      ++diffused;
    }
  }
  // Two captions in a row on the biped: the second segment goes on from the codes of the first, and the
  // decoder reads across the seam at 3 s (docs/generation.md, Several captions).
  const auto biped = std::find_if(clips_by_plan.begin(), clips_by_plan.end(),
                                  [](const auto& clip) { return evaluator::body_plan_of_file(clip.first, "") == "biped"; });
  if (biped != clips_by_plan.end()) {
    const PreparedClip target = tat::prepare_target(biped->first, fps, UpAxis::Auto, stance);
    const int64_t steps = static_cast<int64_t>(3.0 * fps) / session.downsampling();
    const std::vector<gpt::Segment> segments{{"a person walks forward", steps}, {"a person turns to the left", steps}};
    const at::Tensor codes = gpt::generate_codes(session, target, segments, 1, sampling).front();
    const std::string result = (models / "generated_two_captions.bvh").string();
    tat::decode_onto(session.tokenizer, session.token_file(codes, segments[0].caption), target, biped->first, {},
                     result);
    generated.push_back(viewer::load_view_clip(result));
    generated.back().captions = {"0-3 s: " + segments[0].caption, "3-6 s: " + segments[1].caption};
  }
  if (!generated.empty()) {
    write_page(models / "generated.html",
               diffused > 0 ? "nec demo: generated from text, one body plan each (the GPT's, then the diffusion model's), "
                              "and two captions in a row"
                            : "nec demo: generated from text, one body plan each, and two captions in a row",
               generated);
    pages.emplace_back("Generate: motion from a caption on each body plan", "models/generated");
  }

  // Retrieval: three queries against the demo's own cache.
  evaluator::EvaluatorSession retrieval = evaluator::open_evaluator(evaluator_dir, "");
  const evaluator::OpenedIndex opened = evaluator::open_retrieval_index(retrieval, cache, evaluator_dir);
  std::vector<viewer::ViewClip> matches;
  for (const std::string query : {"a person walks forward", "a dog runs", "a creature turns to the left"}) {
    const std::vector<evaluator::Match> top = opened.index.nearest_clips(retrieval.embed_captions({query}, "query"), 3, {});
    fmt::print("retrieve \"{}\":", query);
    for (const evaluator::Match& m : top) {
      const int clip = opened.index.clips[static_cast<size_t>(m.row)];
      const CacheClip& c = cache.clips[static_cast<size_t>(clip)];
      fmt::print(" {} ({:.2f})", fs::path(c.source).stem().string(), m.score);
      matches.push_back({fmt::format("\"{}\" {:.2f}", query, m.score), c.captions, cache.clip(clip)});
    }
    fmt::print("\n");
  }
  write_page(models / "retrieved.html", "nec demo: the top 3 clips of the cache for three captions", matches);
  pages.emplace_back("Retrieve: the cache's best clips for three captions", "models/retrieved");
  fmt::print("default models: {} transfers, {} generated clips ({} by diffusion), 3 queries in {:.1f} s ({})\n",
             transfers.size() / 2, generated.size(), diffused, seconds_since(start), models.string());
  return pages;
}

}  // namespace

int run_demo(int argc, char** argv) {
  CommandLine cli("nec demo",
                  "Run the pipeline on built-in data: make a small zoo of procedural creatures, prepare it with\n"
                  "the CMU motion capture files from Debian (and --extra inputs) into a dataset cache, print a\n"
                  "table per body plan, and write normalized and rig-augmented BVH, PNG strips and viewer pages.\n"
                  "With the default models (models/default): transfers between the body plans, motion generated\n"
                  "from each plan's caption (by the GPT and the diffusion model), and three text queries against the cache. DIR/index.html shows all.");
  cli.option("--out", "DIR", "out/demo", "output folder (its zoo/, cache/, bvh/, strips/, models/ and *.html are replaced)");
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
  for (const char* part : {"zoo", "cache", "bvh", "strips", "models"}) {
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
    write_file_atomic((out / "clips.html").string(), viewer::make_view_html(normalized_views, page));
    page.title = "nec demo: rig augmentations of one clip";
    write_file_atomic((out / "augmented.html").string(), viewer::make_view_html(augmented_views, page));
    // 5. The models' uses, and one page that links everything.
    std::vector<std::pair<std::string, std::string>> sections = {{"Data: one normalized clip per body plan", "clips"},
                                                                 {"Rig augmentation of one clip", "augmented"}};
    std::vector<std::pair<std::string, std::string>> clips_by_plan;  // zoo file, short caption
    std::set<zoo::BodyPlan> plans;
    for (const zoo::ZooClip& c : zoo_summary.clips) {
      if (plans.insert(c.plan).second) clips_by_plan.emplace_back((out / "zoo" / c.bvh_file).string(), c.captions.short_text);
    }
    for (const auto& section : run_model_demo(out, clips_by_plan, cache)) sections.push_back(section);
    std::string index = "<!doctype html><meta charset=utf-8><title>nec demo</title><body style=\"font-family:sans-serif\">"
                        "<h1>nec demo</h1>";
    for (const auto& [title, page_stem] : sections) {
      index += fmt::format("<h2>{}</h2><p><a href=\"{}.html\">play</a></p>", title, page_stem);
      // A strip of each normalized clip under the data, the strip of each page's first clip under the others.
      std::vector<std::string> images;
      if (page_stem == "clips") {
        for (const auto& entry : fs::directory_iterator(out / "strips")) images.push_back("strips/" + entry.path().filename().string());
        std::sort(images.begin(), images.end());
      } else if (fs::exists(out / (page_stem + ".png"))) {
        images.push_back(page_stem + ".png");
      }
      for (const std::string& image : images) index += fmt::format("<p><img src=\"{}\" style=\"max-width:100%\"></p>", image);
    }
    write_file_atomic((out / "index.html").string(), index + "</body>\n");
    pages = {(out / "index.html").string(), (out / "clips.html").string(), (out / "augmented.html").string()};
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

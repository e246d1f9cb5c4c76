// nec retrieve: motions of a cache for a caption, or captions for a motion, through the evaluator's index.
#include "command_line.h"
#include "commands.h"
#include "model_options.h"

#include "nec/evaluator/retrieval.h"
#include "nec/evaluator/retrieval_index.h"
#include "nec/corpus/dataset.h"
#include "nec/motion/bvh.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/tat/session.h"
#include "nec/viewer/html.h"

#include <fmt/format.h>

#include <chrono>
#include <filesystem>

namespace nec::app {
namespace {

// Match `rank` as DIR/rank.bvh (the cache's skeleton and motion of the clip) and its first caption as DIR/rank.txt.
void save_match(const std::string& dir, int rank, const DatasetCache& cache, int clip) {
  std::filesystem::create_directories(dir);
  const CacheClip& info = cache.clips[static_cast<size_t>(clip)];
  Clip motion = cache.clip(clip);
  motion.motion.fps = info.fps;
  const std::filesystem::path stem = std::filesystem::path(dir) / std::to_string(rank);
  write_bvh(stem.string() + ".bvh", motion.skeleton, motion.motion);
  write_file_atomic(stem.string() + ".txt", info.captions.empty() ? "" : info.captions.front() + "\n");
}

// The database with the evaluator and its index of the database: what a worker keeps between searches.
struct SearchSession {
  DatasetCache cache;
  evaluator::EvaluatorSession session;
  evaluator::OpenedIndex opened;
};

SearchSession open_search(const std::string& db, const std::string& evaluator_dir, const std::string& glove) {
  SearchSession search{read_cache(db), evaluator::open_evaluator(evaluator_dir, glove), {}};
  search.opened = evaluator::open_retrieval_index(search.session, search.cache, evaluator_dir);
  const evaluator::OpenedIndex& opened = search.opened;
  if (opened.built) {
    fmt::print("indexed {} clips and {} captions{}{}\n", opened.index.clips.size(), opened.index.captions.size(),
               opened.stored ? " into " + opened.path : "", opened.note.empty() ? "" : " (" + opened.note + ")");
  }
  return search;
}

}  // namespace

int run_retrieve(int argc, char** argv) {
  CommandLine cli("nec retrieve",
                  "Text-motion retrieval with a trained evaluator. With a CAPTION: the clips of the database that\n"
                  "match it best (file, clip span, caption, cosine score). With --motion: the database's captions\n"
                  "nearest to a BVH clip. The database's embeddings are computed once and kept in the cache\n"
                  "directory (retrieval-<evaluator>.index), rebuilt when the cache or the evaluator changes.");
  cli.positional("CAPTION", "what to look for, e.g. \"a dog trots to the left\"", false);
  cli.option("--motion", "CLIP", "", "list the captions nearest to this clip (BVH or rigged asset) instead");
  cli.option("--db", "CACHE", "", "dataset cache to search (from `nec prepare`)", true);
  cli.option("--evaluator", "EVAL", "", "evaluator checkpoint (from `nec train evaluator`, e.g. runs/eval/best);\n"
                                        "default: models/default/evaluator");
  cli.option("-k", "K", "5", "how many results");
  cli.option("--caption-weight", "W", "0.5", "how much the database's own captions count against its motions, 0-1:\n"
                                             "the query is also matched with each clip's caption texts by the\n"
                                             "pretrained sentence encoder (0: the motions alone, as the evaluator's\n"
                                             "R-Precision; a clip without captions is ranked by its motion)");
  cli.option("--plan", "PLAN", "", "only clips of this body plan or dataset, e.g. quadruped, dog, bandai");
  cli.option("--view", "PAGE.html", "", "also write a page that plays the matched clips side by side");
  cli.option("--save", "DIR", "", "also write the matched clips as DIR/1.bvh ... DIR/K.bvh (on the skeleton the cache\n"
                                  "holds them on), each with its caption in DIR/N.txt; DIR is made if missing");
  cli.flag("--force", "overwrite files of --save that exist");
  cli.option("--up", "AXIS", "auto", "up axis of --motion: auto, y or z");
  cli.option("--glove", "FILE", "", "imported word vectors (default: the ones `nec text import-glove` wrote)");
  cli.example("nec retrieve \"a dog trots to the left\" --db cache/ --evaluator runs/eval/best -k 5 --view dog.html");
  cli.example("nec retrieve \"a person jumps\" --db cache/ -k 3 --save found/ && nec transfer found/1.bvh --to my_rig.bvh -o jump.bvh");
  cli.example("nec retrieve --motion walk.bvh --db cache/ --evaluator runs/eval/best");
  if (!cli.parse(argc, argv)) return 0;
  const bool by_motion = !cli.value("--motion").empty();
  const std::vector<std::string>& captions = cli.positionals("CAPTION");
  if (by_motion == !captions.empty()) throw UsageError("give either a CAPTION or --motion CLIP");
  const int64_t k = cli.integer("-k");
  if (k < 1) throw UsageError("-k must be >= 1");
  const double caption_weight = cli.number("--caption-weight");
  if (!(caption_weight >= 0.0 && caption_weight <= 1.0)) throw UsageError("--caption-weight must be in [0, 1]");
  const std::string view = cli.value("--view");
  if (!view.empty() && std::filesystem::exists(view)) throw UsageError(view + " exists; choose another --view file");
  const std::string save = cli.value("--save");
  if (!save.empty() && by_motion) throw UsageError("--save writes the clips found for a CAPTION, not for --motion");
  if (!save.empty()) {
    for (int64_t i = 1; i <= k && !cli.is_set("--force"); ++i) {
      for (const char* extension : {".bvh", ".txt"}) {
        const std::filesystem::path file = std::filesystem::path(save) / (std::to_string(i) + extension);
        if (std::filesystem::exists(file)) throw InputError(file.string(), 0, "exists; pass --force to overwrite it");
      }
    }
  }

  const auto start = std::chrono::steady_clock::now();
  const std::string db = cli.value("--db");
  const std::string evaluator_dir = model_or_default(cli.value("--evaluator"), "evaluator", "--evaluator");
  // Keyed by the cache's own files (not the index files a search stores beside them).
  std::string key = files_stamp(evaluator_dir) + "\n" + glove_stamp(cli.value("--glove"));
  for (const char* file : {"manifest.json", "features.f32", "skeletons.bin"}) key += "\n" + files_stamp((std::filesystem::path(db) / file).string());
  const std::shared_ptr<SearchSession> search =
      warm<SearchSession>(WarmKind::Model, key, [&] { return open_search(db, evaluator_dir, cli.value("--glove")); });
  const DatasetCache& cache = search->cache;
  evaluator::EvaluatorSession& session = search->session;
  const evaluator::OpenedIndex& opened = search->opened;
  const auto query_start = std::chrono::steady_clock::now();
  if (by_motion) {
    const PreparedClip clip = tat::prepare_for_model(cli.value("--motion"), cache.fps, cli.up_axis("--up"));
    const std::vector<evaluator::Match> top = opened.index.nearest_captions(session.embed_clip(clip), static_cast<int>(k));
    fmt::print("| rank | score | caption |\n|---|---|---|\n");
    for (size_t i = 0; i < top.size(); ++i) {
      fmt::print("| {} | {:.3f} | {} |\n", i + 1, top[i].score, opened.index.captions[static_cast<size_t>(top[i].row)]);
    }
  } else {
    const std::string plan = cli.value("--plan");
    const std::function<bool(int)> keep = plan.empty() ? std::function<bool(int)>() : [&](int clip) {
      const CacheClip& c = cache.clips[static_cast<size_t>(clip)];
      return c.dataset == plan || evaluator::body_plan_of(c) == plan;
    };
    evaluator::CaptionBlend blend;
    blend.weight = static_cast<float>(caption_weight);
    if (blend.weight > 0.f) blend.text = evaluator::caption_text_vectors({captions.front()}, "the caption");
    const std::vector<evaluator::Match> top = opened.index.nearest_clips(
        session.embed_captions({captions.front()}, "the caption"), static_cast<int>(k), keep, blend);
    if (top.empty()) throw InputError(cli.value("--db"), 0, "has no clip of plan or dataset '" + plan + "'");
    fmt::print("| rank | score | clip | span (s) | caption |\n|---|---|---|---|---|\n");
    std::vector<viewer::ViewClip> views;
    for (size_t i = 0; i < top.size(); ++i) {
      const int clip = opened.index.clips[static_cast<size_t>(top[i].row)];
      const CacheClip& c = cache.clips[static_cast<size_t>(clip)];
      const double from = c.source_frame / c.fps, to = (c.source_frame + c.frame_count) / c.fps;
      fmt::print("| {} | {:.3f} | {} | {:.1f}-{:.1f} | {} |\n", i + 1, top[i].score, c.id, from, to,
                 c.captions.empty() ? "" : c.captions.front());
      if (!view.empty()) views.push_back({fmt::format("{}. {}", i + 1, c.id), c.captions, cache.clip(clip)});
      if (!save.empty()) save_match(save, static_cast<int>(i) + 1, cache, clip);
    }
    if (!save.empty()) fmt::print("wrote {} clips to {}\n", top.size(), save);
    if (!view.empty()) {
      viewer::ViewOptions options;
      options.title = "nec retrieve: " + captions.front();
      write_file_atomic(view, viewer::make_view_html(views, options));
      fmt::print("wrote {}\n", view);
    }
  }
  const auto now = std::chrono::steady_clock::now();
  fmt::print("query {:.1f} ms (total {:.1f} s)\n", std::chrono::duration<double, std::milli>(now - query_start).count(),
             std::chrono::duration<double>(now - start).count());
  return 0;
}

}  // namespace nec::app

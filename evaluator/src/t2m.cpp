// Generated motion against real motion: R-Precision, MM-Dist, FID, Diversity,
// Multimodality, Coverage / Novelty AUC and jitter, per group.
#include "nec/evaluator/t2m.h"

#include "nec/evaluator/retrieval.h"
#include "nec/corpus/captions.h"
#include "nec/motion/error.h"
#include "nec/motion/frame_rate.h"
#include "nec/motion/kinematics.h"
#include "nec/text/caption_text.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <tuple>

namespace nec::evaluator {
namespace {

namespace fs = std::filesystem;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// The jitter of one clip; NaN under 4 frames.
double clip_jitter(const Clip& clip) {
  if (clip.motion.frame_count < 4) return kNan;
  std::vector<Vec3> positions;
  joint_positions(clip.skeleton, clip.motion, positions);
  std::vector<double> flat;
  flat.reserve(positions.size() * 3);
  for (const Vec3& p : positions) flat.insert(flat.end(), {p.x(), p.y(), p.z()});
  return jitter(flat, clip.motion.frame_count, clip.motion.joint_count, clip.motion.fps);
}

// How fast the joints of one clip turn, degrees per second (check_frame_rate: the median over frames of the
// joints' mean turn); NaN under 2 frames. Generated over real: the turning kept (0: a statue).
double clip_turning(const Clip& clip) {
  if (clip.motion.frame_count < 2) return kNan;
  return check_frame_rate(clip).turn_per_second;
}

// Mean of values[rows], leaving out NaN (NaN when nothing is left).
double mean_of(const std::vector<double>& values, const std::vector<int>& rows) {
  double sum = 0;
  int count = 0;
  for (const int r : rows) {
    if (std::isnan(values[static_cast<size_t>(r)])) continue;
    sum += values[static_cast<size_t>(r)];
    ++count;
  }
  return count > 0 ? sum / count : kNan;
}

std::string number(double value, const char* format = "{:.3f}") {
  return std::isnan(value) ? "—" : fmt::format(fmt::runtime(format), value);
}

nlohmann::json maybe(double value) { return std::isnan(value) ? nlohmann::json() : nlohmann::json(value); }

}  // namespace

void T2mOptions::validate() const {
  if (batch_size < 2 || repeats < 1) throw std::invalid_argument("T2mOptions: batch_size must be >= 2 and repeats >= 1");
  if (diversity_pairs < 1 || multimodality_pairs < 1) throw std::invalid_argument("T2mOptions: pairs must be >= 1");
  if (max_window < 1 || window_stride < 1) throw std::invalid_argument("T2mOptions: max_window and window_stride must be >= 1");
}

std::vector<GeneratedClip> read_generated(const std::string& dir, double fps, UpAxis up) {
  if (!fs::is_directory(dir)) throw InputError(dir, 0, "is not a folder of generated BVH files");
  std::vector<std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".bvh") files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError(dir, 0, "has no .bvh files");
  std::vector<GeneratedClip> out;
  for (const std::string& file : files) {
    GeneratedClip clip;
    clip.path = file;
    const fs::path relative = fs::relative(file, dir);
    clip.group = relative.has_parent_path() ? relative.begin()->string() : "";
    clip.plan = body_plan_of_file(file, clip.group);
    CaptionSources sources;
    sources.bandai = false;
    clip.captions = captions_for(file, sources);
    if (clip.captions.empty()) {
      throw InputError(file, 0, "has no caption: write the caption it was generated from into " +
                                    fs::path(file).replace_extension(".txt").string());
    }
    PreprocessOptions options;
    options.target_fps = fps;
    options.up = up;
    clip.prepared = preprocess_file(file, options);
    out.push_back(std::move(clip));
  }
  return out;
}

T2mReport evaluate_t2m(EvaluatorSession& session, const std::vector<GeneratedClip>& generated, const DatasetCache& cache,
                       Split split, const T2mOptions& options) {
  options.validate();
  T2mReport report;
  report.split = std::string(split_name(split));
  const RetrievalSet reference = retrieval_set(cache, split);

  // Embeddings: every generated clip and its first caption, every reference clip.
  std::vector<at::Tensor> parts;
  std::vector<std::string> captions;
  for (const GeneratedClip& clip : generated) {
    parts.push_back(session.embed_clip(clip.prepared));
    captions.push_back(clip.captions.front());
  }
  const Embeddings motion = to_embeddings(torch::cat(parts));
  const Embeddings text = to_embeddings(session.embed_captions(captions, "generated captions"));
  const Embeddings reference_motion = to_embeddings(session.embed_clips(cache, reference.clips));
  // Jitter and turning of every clip, once.
  std::vector<double> generated_jitter, reference_jitter, generated_turning, reference_turning;
  for (const GeneratedClip& clip : generated) {
    generated_jitter.push_back(clip_jitter(clip.prepared.clip));
    generated_turning.push_back(clip_turning(clip.prepared.clip));
  }
  for (const int index : reference.clips) {
    const Clip clip = cache.clip(index);
    reference_jitter.push_back(clip_jitter(clip));
    reference_turning.push_back(clip_turning(clip));
  }

  std::map<std::string, std::vector<int>> groups;
  for (size_t i = 0; i < generated.size(); ++i) {
    if (!generated[i].group.empty()) groups[generated[i].group].push_back(static_cast<int>(i));
    groups["all"].push_back(static_cast<int>(i));
  }
  // Captions as Coverage / Novelty matches them, once per clip (not per generated x reference pair).
  const auto caption_key = [&](const std::string& caption) {
    const std::string normalized = text::normalize_caption(caption);
    return options.coverage_across_creatures ? mask_creature_words(normalized) : normalized;
  };
  std::vector<std::string> generated_caption_keys;
  for (const GeneratedClip& clip : generated) generated_caption_keys.push_back(caption_key(clip.captions.front()));
  std::vector<std::vector<std::string>> reference_caption_keys;
  for (const int clip : reference.clips) {
    std::vector<std::string>& keys = reference_caption_keys.emplace_back();
    for (const std::string& caption : cache.clips[static_cast<size_t>(clip)].captions) keys.push_back(caption_key(caption));
  }
  // Window embeddings of a clip at one window length, computed once: a reference clip meets many generated
  // clips, and every clip comes back in the "all" row. Keys: (generated?, clip index, window frames).
  std::map<std::tuple<bool, int, int>, Embeddings> windows;
  const auto windows_of = [&](bool is_generated, int index, int window) -> const Embeddings& {
    auto [it, added] = windows.try_emplace({is_generated, index, window});
    if (!added) return it->second;
    if (is_generated) {
      const PreparedClip& prepared = generated[static_cast<size_t>(index)].prepared;
      it->second = to_embeddings(session.embed_clip_windows(
          prepared, window_starts(prepared.clip.motion.frame_count, window, options.window_stride), window));
    } else {
      it->second = to_embeddings(session.embed_windows(
          cache, index, window_starts(cache.clips[static_cast<size_t>(index)].frame_count, window, options.window_stride),
          window));
    }
    return it->second;
  };
  std::vector<std::string> names;
  for (const auto& [name, rows] : groups) {
    if (name != "all") names.push_back(name);
  }
  names.push_back("all");
  for (const std::string& name : names) {
    const std::vector<int>& rows = groups[name];
    std::vector<int> reference_rows;
    for (size_t r = 0; r < reference.clips.size(); ++r) {
      if (reference.datasets[r] == name) reference_rows.push_back(static_cast<int>(r));
    }
    if (reference_rows.empty()) {
      for (size_t r = 0; r < reference.clips.size(); ++r) reference_rows.push_back(static_cast<int>(r));
    }
    T2mRow row;
    row.name = name;
    row.generated = static_cast<int>(rows.size());
    row.reference = static_cast<int>(reference_rows.size());
    const Embeddings g = rows_of(motion, rows), ref = rows_of(reference_motion, reference_rows);
    if (rows.size() >= 2) {
      RPrecisionOptions r;
      r.batch_size = std::min<int>(options.batch_size, row.generated);
      r.repeats = options.repeats;
      r.seed = options.seed;
      r.top_k = std::min(3, r.batch_size);
      row.batch_size = r.batch_size;
      row.precision = r_precision(rows_of(text, rows), g, r);
      row.has_precision = true;
      // Within plan: r_precision_within_groups needs one plan with a full batch.
      std::vector<std::string> plans;
      std::map<std::string, int> plan_sizes;
      for (const int i : rows) ++plan_sizes[plans.emplace_back(generated[static_cast<size_t>(i)].plan)];
      r.batch_size = options.batch_size;
      row.has_within_plan = std::any_of(plan_sizes.begin(), plan_sizes.end(),
                                        [&](const auto& plan) { return plan.second >= r.batch_size; });
      if (row.has_within_plan) row.within_plan = r_precision_within_groups(rows_of(text, rows), g, plans, r);
      row.diversity = diversity(g, {options.diversity_pairs, options.seed});
    } else {
      row.diversity = kNan;
    }
    row.fid = rows.size() >= 2 && ref.rows() >= 2 ? fid(g, ref) : kNan;
    row.reference_diversity = ref.rows() >= 2 ? diversity(ref, {options.diversity_pairs, options.seed}) : kNan;

    // Multimodality: the samples of each caption.
    std::map<std::string, std::vector<int>> by_caption;
    for (const int i : rows) by_caption[text::normalize_caption(captions[static_cast<size_t>(i)])].push_back(i);
    std::vector<Embeddings> samples;
    for (const auto& [caption, items] : by_caption) {
      if (items.size() >= 2) samples.push_back(rows_of(motion, items));
    }
    row.multimodality_captions = static_cast<int>(samples.size());
    row.multimodality = samples.empty() ? kNan : multimodality(samples, {options.multimodality_pairs, options.seed});

    // Coverage and Novelty of each generated clip against the reference clips that carry its caption.
    double coverage = 0, novelty = 0;
    for (const int i : rows) {
      const GeneratedClip& clip = generated[static_cast<size_t>(i)];
      const std::string& wanted = generated_caption_keys[static_cast<size_t>(i)];
      for (const int r : reference_rows) {
        const CacheClip& real = cache.clips[static_cast<size_t>(reference.clips[static_cast<size_t>(r)])];
        const std::vector<std::string>& keys = reference_caption_keys[static_cast<size_t>(r)];
        const bool same = std::find(keys.begin(), keys.end(), wanted) != keys.end();
        if (!same) continue;
        const int window = std::min<int>(window_length(real.frame_count, clip.prepared.clip.motion.frame_count,
                                                       options.max_window),
                                         static_cast<int>(session.loaded().model->config().motion.max_frames()));
        const CoverageNovelty cn =
            coverage_novelty(windows_of(false, reference.clips[static_cast<size_t>(r)], window), windows_of(true, i, window));
        coverage += cn.coverage_auc;
        novelty += cn.novelty_auc;
        ++row.coverage_pairs;
      }
    }
    row.coverage_auc = row.coverage_pairs > 0 ? coverage / row.coverage_pairs : kNan;
    row.novelty_auc = row.coverage_pairs > 0 ? novelty / row.coverage_pairs : kNan;

    row.jitter = mean_of(generated_jitter, rows);
    row.reference_jitter = mean_of(reference_jitter, reference_rows);
    row.turning = mean_of(generated_turning, rows);
    row.reference_turning = mean_of(reference_turning, reference_rows);
    report.rows.push_back(std::move(row));
  }
  return report;
}

std::string to_markdown(const T2mReport& report) {
  std::string out = fmt::format(
      "| group | generated / {} clips | R@1 / R@2 / R@3 (batch) | within plan R@3 | MM-Dist | FID | Diversity (real) | "
      "Multimodality (captions) | Coverage AUC | Novelty AUC | jitter (real) | turning °/s (real) |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n",
      report.split);
  for (const T2mRow& row : report.rows) {
    std::string precision = "—", mm_dist = "—", within_plan = "—";
    if (row.has_precision) {
      precision.clear();
      for (const Interval& i : row.precision.top_k) precision += (precision.empty() ? "" : " / ") + fmt::format("{:.3f}", i.mean);
      precision += fmt::format(" ({})", row.batch_size);
      mm_dist = number(row.precision.mm_dist.mean);
    }
    if (row.has_within_plan) within_plan = number(row.within_plan.top_k.back().mean);
    out += fmt::format("| {} | {} / {} | {} | {} | {} | {} | {} ({}) | {} ({}) | {} | {} | {} ({}) | {} ({}) |\n", row.name,
                       row.generated, row.reference, precision, within_plan, mm_dist, number(row.fid), number(row.diversity),
                       number(row.reference_diversity), number(row.multimodality), row.multimodality_captions,
                       number(row.coverage_auc), number(row.novelty_auc), number(row.jitter, "{:.1f}"),
                       number(row.reference_jitter, "{:.1f}"), number(row.turning, "{:.1f}"),
                       number(row.reference_turning, "{:.1f}"));
  }
  return out;
}

nlohmann::json to_json(const T2mReport& report) {
  nlohmann::json rows = nlohmann::json::array();
  for (const T2mRow& row : report.rows) {
    nlohmann::json r = {{"name", row.name},
                        {"generated", row.generated},
                        {"reference", row.reference},
                        {"fid", maybe(row.fid)},
                        {"diversity", maybe(row.diversity)},
                        {"reference_diversity", maybe(row.reference_diversity)},
                        {"multimodality", maybe(row.multimodality)},
                        {"multimodality_captions", row.multimodality_captions},
                        {"coverage_auc", maybe(row.coverage_auc)},
                        {"novelty_auc", maybe(row.novelty_auc)},
                        {"coverage_pairs", row.coverage_pairs},
                        {"jitter", maybe(row.jitter)},
                        {"reference_jitter", maybe(row.reference_jitter)},
                        {"turning", maybe(row.turning)},
                        {"reference_turning", maybe(row.reference_turning)}};
    if (row.has_precision) {
      r["precision"] = to_json(row.precision);
      r["batch_size"] = row.batch_size;
    }
    if (row.has_within_plan) r["within_plan"] = to_json(row.within_plan);
    rows.push_back(std::move(r));
  }
  return {{"split", report.split}, {"rows", rows}};
}

}  // namespace nec::evaluator

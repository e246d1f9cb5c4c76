// R-Precision tables over a cache: mixed, within plan, creature words masked, floor.
#include "nec/evaluator/retrieval.h"

#include "nec/corpus/batch.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/random.h"
#include "nec/text/caption_text.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <regex>
#include <set>

namespace nec::evaluator {
namespace {

constexpr size_t kDecodedBatch = 32;  // decoded clips embedded together

// R-Precision with the captions shuffled among the motions: a new shuffle for
// every repeat (one fixed shuffle would be one draw of chance, not chance).
RPrecision shuffled_floor(const Embeddings& text, const Embeddings& motion, const RPrecisionOptions& options) {
  std::vector<std::vector<double>> top(static_cast<size_t>(options.top_k));
  std::vector<double> distances;
  RPrecision out;
  for (int repeat = 0; repeat < options.repeats; ++repeat) {
    std::vector<int> order(static_cast<size_t>(motion.rows()));
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
    SplitMix64 random(mix64(options.seed ^ mix64(0x5EEDull + static_cast<uint64_t>(repeat))));
    random.shuffle(order);
    RPrecisionOptions once = options;
    once.repeats = 1;
    once.seed = mix64(options.seed ^ static_cast<uint64_t>(repeat));
    const RPrecision r = r_precision(text, rows_of(motion, order), once);
    for (size_t k = 0; k < top.size(); ++k) top[k].push_back(r.top_k[k].mean);
    distances.push_back(r.mm_dist.mean);
    out.batches_per_repeat = r.batches_per_repeat;
  }
  for (const std::vector<double>& values : top) out.top_k.push_back(interval_of(values));
  out.mm_dist = interval_of(distances);
  return out;
}

std::string interval_text(const Interval& i) { return fmt::format("{:.3f} ± {:.3f}", i.mean, i.half_width); }

}  // namespace

std::string body_plan_of_file(const std::string& path, const std::string& dataset) {
  static const std::regex zoo_folder("^c[0-9]+_([a-z]+)$");
  std::smatch match;
  const std::string folder = std::filesystem::path(path).parent_path().filename().string();
  if (std::regex_match(folder, match, zoo_folder)) return match[1].str();
  return dataset;
}

std::string body_plan_of(const CacheClip& clip) { return body_plan_of_file(clip.source, clip.dataset); }

const std::vector<std::string>& creature_words() {
  static const std::vector<std::string> words{
      "person", "someone", "human", "man", "woman", "people", "dog", "cat", "horse", "wolf", "bear", "dragon",
      "bird", "fish", "snake", "ant", "beetle", "insect", "spider", "centipede", "biped", "quadruped", "hexapod",
      "creature", "animal", "beast", "monster", "serpent", "reptile", "lizard"};
  return words;
}

std::string mask_creature_words(const std::string& normalized_caption, const std::string& replacement) {
  static const std::set<std::string> nouns = [] {
    std::set<std::string> out;
    for (const std::string& w : creature_words()) {
      out.insert(w);
      out.insert(w + "s");
    }
    out.insert("people");
    return out;
  }();
  std::string out;
  for (const std::string& word : text::caption_words(normalized_caption)) {
    if (!out.empty()) out += ' ';
    out += nouns.count(word) ? replacement : word;
  }
  return out;
}

std::string creature_noun_of(const DatasetCache& cache, const std::string& dataset) {
  const std::set<std::string> nouns(creature_words().begin(), creature_words().end());
  std::map<std::string, int> counts;
  for (const CacheClip& clip : cache.clips) {
    if (clip.dataset != dataset) continue;
    for (const std::string& caption : clip.captions) {
      for (const std::string& word : text::caption_words(text::normalize_caption(caption))) {
        if (nouns.count(word)) ++counts[word];
      }
    }
  }
  std::string best;
  for (const auto& [word, count] : counts) {
    if (best.empty() || count > counts[best]) best = word;
  }
  return best;
}

at::Tensor embed_through_tokenizer(EvaluatorSession& session, tat::TokenizerSession& tokenizer, const DatasetCache& cache,
                                   const std::vector<int>& clips, const std::vector<int>& targets) {
  if (clips.size() != targets.size()) throw std::invalid_argument("embed_through_tokenizer: one target per clip");
  std::map<int, at::Tensor> embeddings;  // per skeleton of the cache
  const auto embedding_of = [&](int skeleton) -> const at::Tensor& {
    auto found = embeddings.find(skeleton);
    if (found == embeddings.end()) {
      const CachedSkeleton& s = cache.skeletons.at(static_cast<size_t>(skeleton));
      found = embeddings.emplace(skeleton, tokenizer.embed(s.skeleton, s.canonical_names)).first;
    }
    return found->second;
  };
  const int max_frames = static_cast<int>(session.loaded().model->config().motion.max_frames());
  std::vector<at::Tensor> parts;
  std::vector<MotionInput> decoded;
  for (size_t i = 0; i < clips.size(); ++i) {
    const CacheClip& clip = cache.clips.at(static_cast<size_t>(clips[i]));
    const int target = targets[i] < 0 ? clip.skeleton : targets[i];
    const CachedSkeleton& skeleton = cache.skeletons.at(static_cast<size_t>(target));
    const int count = std::min(clip.frame_count, max_frames);
    const Features source = crop_at_start_heading(cache, clips[i], (clip.frame_count - count) / 2, count);
    c10::InferenceMode inference;
    const at::Tensor codes = tat::encode_clip(*tokenizer.model.tokenizer, source, embedding_of(clip.skeleton), tokenizer.windows);
    decoded.push_back({tat::decode_clip(*tokenizer.model.tokenizer, codes, count, embedding_of(target), skeleton.skeleton,
                                        cache.fps, tokenizer.windows),
                       &skeleton.skeleton, &skeleton.canonical_names});
    if (decoded.size() == kDecodedBatch || i + 1 == clips.size()) {
      parts.push_back(session.embed_motion_inputs(decoded));
      decoded.clear();
    }
  }
  return parts.empty() ? torch::zeros({0, session.dim()}) : torch::cat(parts);
}

RetrievalSet retrieval_set(const DatasetCache& cache, Split split) {
  RetrievalSet set;
  for (const int clip : cache.clips_in(split)) {
    const CacheClip& c = cache.clips[static_cast<size_t>(clip)];
    if (c.captions.empty()) continue;
    set.clips.push_back(clip);
    set.captions.push_back(c.captions.front());
    set.datasets.push_back(c.dataset);
    set.plans.push_back(body_plan_of(c));
  }
  return set;
}

std::vector<std::pair<std::string, std::string>> read_file_captions(const std::string& path) {
  std::vector<std::pair<std::string, std::string>> out;
  std::set<std::string> seen;
  const std::string text = read_file(path, size_t{1} << 26);
  size_t start = 0;
  for (int line_number = 1; start < text.size(); ++line_number) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    start = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const size_t tab = line.find('\t');
    if (tab == std::string::npos || tab == 0 || tab + 1 == line.size()) {
      throw InputError(path, line_number, "expected 'file name<TAB>caption'");
    }
    const std::string file = line.substr(0, tab);
    if (!seen.insert(file).second) throw InputError(path, line_number, "'" + file + "' is named twice");
    out.emplace_back(file, line.substr(tab + 1));
  }
  return out;
}

RetrievalSet with_captions(const RetrievalSet& set, const DatasetCache& cache,
                           const std::vector<std::pair<std::string, std::string>>& captions, const std::string& path) {
  std::map<std::string, size_t> row_of_file;
  for (size_t i = 0; i < set.clips.size(); ++i) {
    const std::string file = std::filesystem::path(cache.clips[static_cast<size_t>(set.clips[i])].source).filename().string();
    row_of_file.emplace(file, i);
  }
  RetrievalSet out;
  for (const auto& [file, caption] : captions) {
    const auto found = row_of_file.find(file);
    if (found == row_of_file.end()) throw InputError(path, 0, "'" + file + "' is not a captioned clip of this split");
    const size_t i = found->second;
    out.clips.push_back(set.clips[i]);
    out.captions.push_back(caption);
    out.datasets.push_back(set.datasets[i]);
    out.plans.push_back(set.plans[i]);
  }
  return out;
}

RetrievalTable retrieval_table(const RetrievalSet& set, const RetrievalEmbeddings& embeddings,
                               const RetrievalOptions& options) {
  const Embeddings& text = embeddings.text;
  const Embeddings& masked_text = embeddings.masked_text;
  const Embeddings& motion = embeddings.motion;
  RetrievalTable table;
  std::map<std::string, std::vector<int>> groups;
  for (size_t i = 0; i < set.clips.size(); ++i) {
    groups[set.datasets[i]].push_back(static_cast<int>(i));
    groups["all"].push_back(static_cast<int>(i));
  }
  std::vector<std::string> names;
  for (const auto& [name, rows] : groups) {
    if (name != "all") names.push_back(name);
  }
  names.push_back("all");
  for (const std::string& name : names) {
    const std::vector<int>& rows = groups[name];
    if (rows.size() < 2) continue;
    RetrievalRow row;
    row.name = name;
    row.clips = static_cast<int>(rows.size());
    row.batch_size = std::min<int>(options.batch_size, row.clips);
    RPrecisionOptions r;
    r.batch_size = row.batch_size;
    r.repeats = options.repeats;
    r.seed = options.seed;
    r.top_k = std::min(3, row.batch_size);
    const Embeddings t = rows_of(text, rows), m = rows_of(motion, rows);
    row.mixed = r_precision(t, m, r);
    row.masked = r_precision(rows_of(masked_text, rows), m, r);
    row.floor = shuffled_floor(t, m, r);
    std::vector<std::string> plans;
    for (const int i : rows) plans.push_back(set.plans[static_cast<size_t>(i)]);
    try {
      row.within_plan = r_precision_within_groups(t, m, plans, r);
      row.has_within_plan = true;
    } catch (const std::invalid_argument&) {
      row.has_within_plan = false;  // no plan has a batch's worth of clips
    }
    table.rows.push_back(std::move(row));
  }
  return table;
}

RetrievalEmbeddings embed_set_captions(EvaluatorSession& session, const RetrievalSet& set) {
  std::vector<std::string> masked;
  for (const std::string& caption : set.captions) masked.push_back(mask_creature_words(text::normalize_caption(caption)));
  return {to_embeddings(session.embed_captions(set.captions, "captions")),
          to_embeddings(session.embed_captions(masked, "masked captions")), Embeddings()};
}

RetrievalEmbeddings embed_retrieval_set(EvaluatorSession& session, const DatasetCache& cache, const RetrievalSet& set) {
  RetrievalEmbeddings out = embed_set_captions(session, set);
  out.motion = to_embeddings(session.embed_clips(cache, set.clips));
  return out;
}

nlohmann::json to_json(const RPrecision& r) {
  nlohmann::json top = nlohmann::json::array();
  for (const Interval& i : r.top_k) top.push_back({{"mean", i.mean}, {"half_width", i.half_width}});
  return {{"r_precision", top},
          {"mm_dist", {{"mean", r.mm_dist.mean}, {"half_width", r.mm_dist.half_width}}},
          {"batches_per_repeat", r.batches_per_repeat},
          {"skipped_groups", r.skipped_groups}};
}

std::string to_markdown(const RetrievalTable& table) {
  std::string out = fmt::format(
      "| {} split | clips | batch | mixed R@1 / R@2 / R@3 | within plan R@3 | creature words masked R@3 | floor R@3 | MM-Dist |\n"
      "|---|---|---|---|---|---|---|---|\n",
      table.split);
  for (const RetrievalRow& row : table.rows) {
    const auto r3 = [](const RPrecision& r) { return interval_text(r.top_k.back()); };
    std::string top;
    for (const Interval& i : row.mixed.top_k) top += (top.empty() ? "" : " / ") + fmt::format("{:.3f}", i.mean);
    out += fmt::format("| {} | {} | {} | {} (± {:.3f}) | {} | {} | {} | {:.3f} |\n", row.name, row.clips, row.batch_size,
                       top, row.mixed.top_k.back().half_width, row.has_within_plan ? r3(row.within_plan) : "—",
                       r3(row.masked), r3(row.floor), row.mixed.mm_dist.mean);
  }
  return out;
}

nlohmann::json to_json(const RetrievalTable& table) {
  nlohmann::json rows = nlohmann::json::array();
  for (const RetrievalRow& row : table.rows) {
    nlohmann::json r = {{"name", row.name},
                        {"clips", row.clips},
                        {"batch_size", row.batch_size},
                        {"mixed", to_json(row.mixed)},
                        {"creature_words_masked", to_json(row.masked)},
                        {"floor", to_json(row.floor)}};
    if (row.has_within_plan) r["within_plan"] = to_json(row.within_plan);
    rows.push_back(std::move(r));
  }
  return {{"split", table.split}, {"rows", rows}};
}

}  // namespace nec::evaluator

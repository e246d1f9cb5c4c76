// R-Precision tables over a cache: mixed, within plan, creature words masked, floor.
#include "nec/evaluator/retrieval.h"

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

// Rows of `all` picked by `rows`.
Embeddings pick(const Embeddings& all, const std::vector<int>& rows) {
  Embeddings out(static_cast<Eigen::Index>(rows.size()), all.cols());
  for (size_t i = 0; i < rows.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = all.row(rows[i]);
  return out;
}

std::string interval_text(const Interval& i) { return fmt::format("{:.3f} ± {:.3f}", i.mean, i.half_width); }

nlohmann::json precision_json(const RPrecision& r) {
  nlohmann::json top = nlohmann::json::array();
  for (const Interval& i : r.top_k) top.push_back({{"mean", i.mean}, {"half_width", i.half_width}});
  return {{"r_precision", top},
          {"mm_dist", {{"mean", r.mm_dist.mean}, {"half_width", r.mm_dist.half_width}}},
          {"batches_per_repeat", r.batches_per_repeat},
          {"skipped_groups", r.skipped_groups}};
}

}  // namespace

std::string body_plan_of(const CacheClip& clip) {
  static const std::regex zoo_folder("^c[0-9]+_([a-z]+)$");
  std::smatch match;
  const std::string folder = std::filesystem::path(clip.source).parent_path().filename().string();
  if (std::regex_match(folder, match, zoo_folder)) return match[1].str();
  return clip.dataset;
}

const std::vector<std::string>& creature_words() {
  static const std::vector<std::string> words{
      "person", "someone", "human", "man", "woman", "people", "dog", "cat", "horse", "wolf", "bear", "dragon",
      "bird", "fish", "snake", "ant", "beetle", "insect", "spider", "centipede", "biped", "quadruped", "hexapod",
      "creature", "animal"};
  return words;
}

std::string mask_creature_words(const std::string& normalized_caption) {
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
    out += nouns.count(word) ? "creature" : word;
  }
  return out;
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

RetrievalTable retrieval_table(const RetrievalSet& set, const Embeddings& text, const Embeddings& masked_text,
                               const Embeddings& motion, const RetrievalOptions& options) {
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
    const Embeddings t = pick(text, rows), m = pick(motion, rows);
    row.mixed = r_precision(t, m, r);
    row.masked = r_precision(pick(masked_text, rows), m, r);
    // The floor: every text against a motion drawn by a fixed shuffle of the rows.
    std::vector<int> shuffled(rows.size());
    for (size_t i = 0; i < rows.size(); ++i) shuffled[i] = static_cast<int>(i);
    SplitMix64 random(mix64(options.seed ^ 0x5EED));
    random.shuffle(shuffled);
    row.floor = r_precision(t, pick(m, shuffled), r);
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

RetrievalTable retrieval_table(EvaluatorSession& session, const DatasetCache& cache, const RetrievalSet& set,
                               const RetrievalOptions& options) {
  std::vector<std::string> masked;
  for (const std::string& caption : set.captions) masked.push_back(mask_creature_words(text::normalize_caption(caption)));
  const Embeddings text = to_embeddings(session.embed_captions(set.captions, "cache captions"));
  const Embeddings masked_text = to_embeddings(session.embed_captions(masked, "masked cache captions"));
  const Embeddings motion = to_embeddings(session.embed_clips(cache, set.clips));
  return retrieval_table(set, text, masked_text, motion, options);
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
                        {"mixed", precision_json(row.mixed)},
                        {"creature_words_masked", precision_json(row.masked)},
                        {"floor", precision_json(row.floor)}};
    if (row.has_within_plan) r["within_plan"] = precision_json(row.within_plan);
    rows.push_back(std::move(r));
  }
  return {{"split", table.split}, {"rows", rows}};
}

}  // namespace nec::evaluator

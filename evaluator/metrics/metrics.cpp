// Ranking and sampling metrics: intervals over repeats, R-Precision and MM-Dist,
// Diversity and Multimodality (Guo et al. 2022). See metrics.h.
#include "nec/evaluator/metrics.h"

#include "embedding_checks.h"
#include "nec/motion/random.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>

namespace nec::evaluator {

Embeddings rows_of(const Embeddings& all, const std::vector<int>& rows) {
  Embeddings out(static_cast<Eigen::Index>(rows.size()), all.cols());
  for (size_t i = 0; i < rows.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = all.row(rows[i]);
  return out;
}

namespace {

void require_pairs(const Embeddings& text, const Embeddings& motion, const std::string& what) {
  require_embeddings(text, what + " text", 1);
  require_embeddings(motion, what + " motion", 1);
  if (text.rows() != motion.rows() || text.cols() != motion.cols()) {
    throw std::invalid_argument(what + ": text is " + std::to_string(text.rows()) + " x " + std::to_string(text.cols()) +
                                " but motion is " + std::to_string(motion.rows()) + " x " +
                                std::to_string(motion.cols()) + "; row i of each must be a matched pair");
  }
}

// Adds R@1..R@top_k and the matched distance of every text in one batch.
void score_batch(const Embeddings& text, const Embeddings& motion, const std::vector<int>& batch, int top_k,
                 std::vector<double>& hits, double& matched_distance_sum) {
  const int size = static_cast<int>(batch.size());
  std::vector<double> distances(size);
  for (int i = 0; i < size; ++i) {
    for (int j = 0; j < size; ++j) distances[j] = (text.row(batch[i]) - motion.row(batch[j])).norm();
    const double matched = distances[i];
    int closer = 0, tied = 0;
    for (int j = 0; j < size; ++j) {
      if (j == i) continue;
      if (distances[j] < matched) ++closer;
      if (distances[j] == matched) ++tied;
    }
    for (int k = 1; k <= top_k; ++k) {
      hits[k - 1] += std::clamp(static_cast<double>(k - closer) / (tied + 1), 0.0, 1.0);
    }
    matched_distance_sum += matched;
  }
}

// groups_items: the item indices of each group, in group order.
RPrecision r_precision_of_groups(const Embeddings& text, const Embeddings& motion,
                                 const std::vector<std::vector<int>>& groups_items, const RPrecisionOptions& options) {
  const int batch_size = options.batch_size;
  std::vector<std::vector<double>> hits_per_repeat(options.top_k);
  std::vector<double> mm_dist_per_repeat;
  RPrecision result;
  for (int repeat = 0; repeat < options.repeats; ++repeat) {
    SplitMix64 random(mix64(options.seed ^ mix64(static_cast<uint64_t>(repeat))));
    std::vector<double> hits(options.top_k, 0.0);
    double matched_distance_sum = 0.0;
    int batches = 0;
    for (std::vector<int> items : groups_items) {  // a copy: each repeat shuffles from the same order
      if (static_cast<int>(items.size()) < batch_size) continue;
      random.shuffle(items);
      for (size_t start = 0; start + batch_size <= items.size(); start += batch_size) {
        const std::vector<int> batch(items.begin() + start, items.begin() + start + batch_size);
        score_batch(text, motion, batch, options.top_k, hits, matched_distance_sum);
        ++batches;
      }
    }
    const double texts = static_cast<double>(batches) * batch_size;
    for (int k = 0; k < options.top_k; ++k) hits_per_repeat[k].push_back(hits[k] / texts);
    mm_dist_per_repeat.push_back(matched_distance_sum / texts);
    result.batches_per_repeat = batches;
  }
  for (const std::vector<double>& hits : hits_per_repeat) result.top_k.push_back(interval_of(hits));
  result.mm_dist = interval_of(mm_dist_per_repeat);
  return result;
}

double mean_pair_distance(const Embeddings& embeddings, const IndexPairs& pairs) {
  double sum = 0.0;
  for (size_t i = 0; i < pairs.first.size(); ++i) sum += (embeddings.row(pairs.first[i]) - embeddings.row(pairs.second[i])).norm();
  return sum / static_cast<double>(pairs.first.size());
}

}  // namespace

Interval interval_of(const std::vector<double>& values) {
  if (values.empty()) throw std::invalid_argument("interval_of: needs at least one value");
  const double n = static_cast<double>(values.size());
  const double mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
  if (values.size() == 1) return {mean, 0.0};
  double squares = 0.0;
  for (double v : values) squares += (v - mean) * (v - mean);
  const double std_dev = std::sqrt(squares / (n - 1.0));
  return {mean, 1.96 * std_dev / std::sqrt(n)};
}

void RPrecisionOptions::validate() const {
  if (batch_size < 2) throw std::invalid_argument("RPrecisionOptions: batch_size must be at least 2, is " + std::to_string(batch_size));
  if (repeats < 1) throw std::invalid_argument("RPrecisionOptions: repeats must be at least 1, is " + std::to_string(repeats));
  if (top_k < 1 || top_k > batch_size) {
    throw std::invalid_argument("RPrecisionOptions: top_k must be in [1, batch_size = " + std::to_string(batch_size) +
                                "], is " + std::to_string(top_k));
  }
}

RPrecision r_precision(const Embeddings& text, const Embeddings& motion, const RPrecisionOptions& options) {
  options.validate();
  require_pairs(text, motion, "r_precision");
  const int items = static_cast<int>(text.rows());
  if (items < options.batch_size) {
    throw std::invalid_argument("r_precision: " + std::to_string(items) + " items form no batch of batch_size " +
                                std::to_string(options.batch_size));
  }
  std::vector<int> all(items);
  std::iota(all.begin(), all.end(), 0);
  return r_precision_of_groups(text, motion, {all}, options);
}

RPrecision r_precision_within_groups(const Embeddings& text, const Embeddings& motion,
                                     const std::vector<std::string>& groups, const RPrecisionOptions& options) {
  options.validate();
  require_pairs(text, motion, "r_precision_within_groups");
  if (static_cast<Eigen::Index>(groups.size()) != text.rows()) {
    throw std::invalid_argument("r_precision_within_groups: " + std::to_string(groups.size()) + " group labels for " +
                                std::to_string(text.rows()) + " rows; needs one per row");
  }
  std::map<std::string, std::vector<int>> items_by_group;  // sorted: the batches do not depend on label order
  for (size_t i = 0; i < groups.size(); ++i) items_by_group[groups[i]].push_back(static_cast<int>(i));
  std::vector<std::vector<int>> groups_items;
  std::vector<std::string> skipped;
  size_t largest = 0;
  for (const auto& [name, items] : items_by_group) {
    largest = std::max(largest, items.size());
    if (static_cast<int>(items.size()) < options.batch_size) {
      skipped.push_back(name);
    } else {
      groups_items.push_back(items);
    }
  }
  if (groups_items.empty()) {
    throw std::invalid_argument("r_precision_within_groups: " + std::to_string(groups.size()) + " items in " +
                                std::to_string(items_by_group.size()) + " groups (largest " + std::to_string(largest) +
                                ") form no batch of batch_size " + std::to_string(options.batch_size));
  }
  RPrecision result = r_precision_of_groups(text, motion, groups_items, options);
  result.skipped_groups = std::move(skipped);
  return result;
}

double r_precision_chance(int k, int batch_size) {
  if (batch_size < 1 || k < 1 || k > batch_size) {
    throw std::invalid_argument("r_precision_chance: needs 1 <= k <= batch_size, has k = " + std::to_string(k) +
                                ", batch_size = " + std::to_string(batch_size));
  }
  return static_cast<double>(k) / batch_size;
}

IndexPairs draw_pairs(int rows, int pairs, uint64_t seed) {
  if (rows < 1 || pairs < 1) {
    throw std::invalid_argument("draw_pairs: needs rows >= 1 and pairs >= 1, has rows = " + std::to_string(rows) +
                                ", pairs = " + std::to_string(pairs));
  }
  SplitMix64 random(mix64(seed));
  const auto draw_list = [&] {
    std::vector<int> list(pairs);
    if (rows < pairs) {
      for (int& index : list) index = static_cast<int>(random.below(rows));
      return list;
    }
    // The first `pairs` steps of a Fisher-Yates shuffle: distinct rows.
    std::vector<int> order(rows);
    std::iota(order.begin(), order.end(), 0);
    for (int i = 0; i < pairs; ++i) {
      std::swap(order[i], order[i + random.below(static_cast<uint64_t>(rows - i))]);
      list[i] = order[i];
    }
    return list;
  };
  IndexPairs result;
  result.first = draw_list();
  result.second = draw_list();
  return result;
}

void DiversityOptions::validate() const {
  if (pairs < 1) throw std::invalid_argument("DiversityOptions: pairs must be at least 1, is " + std::to_string(pairs));
}

double diversity(const Embeddings& embeddings, const DiversityOptions& options) {
  options.validate();
  require_embeddings(embeddings, "diversity", 2);
  return mean_pair_distance(embeddings, draw_pairs(static_cast<int>(embeddings.rows()), options.pairs, options.seed));
}

void MultimodalityOptions::validate() const {
  if (pairs < 1) throw std::invalid_argument("MultimodalityOptions: pairs must be at least 1, is " + std::to_string(pairs));
}

double multimodality(const std::vector<Embeddings>& samples_per_caption, const MultimodalityOptions& options) {
  options.validate();
  if (samples_per_caption.empty()) throw std::invalid_argument("multimodality: needs at least one caption");
  double sum = 0.0;
  for (size_t caption = 0; caption < samples_per_caption.size(); ++caption) {
    const Embeddings& samples = samples_per_caption[caption];
    require_embeddings(samples, "multimodality caption " + std::to_string(caption), 2);
    if (samples.cols() != samples_per_caption[0].cols()) {
      throw std::invalid_argument("multimodality: caption " + std::to_string(caption) + " has " +
                                  std::to_string(samples.cols()) + " columns, caption 0 has " +
                                  std::to_string(samples_per_caption[0].cols()));
    }
    const uint64_t caption_seed = mix64(options.seed ^ mix64(static_cast<uint64_t>(caption)));
    sum += mean_pair_distance(samples, draw_pairs(static_cast<int>(samples.rows()), options.pairs, caption_seed));
  }
  return sum / static_cast<double>(samples_per_caption.size());
}

}  // namespace nec::evaluator

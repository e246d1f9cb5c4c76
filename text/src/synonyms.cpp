// Caption synonyms from word-vector neighbours: the table and the rewrite.
#include "nec/text/synonyms.h"

#include "nec/text/caption_text.h"

#include <Eigen/Core>

#include <algorithm>
#include <set>
#include <stdexcept>
#include <utility>

namespace nec::text {
namespace {

using RowMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

bool lower_letters_only(std::string_view word) {
  return !word.empty() && std::all_of(word.begin(), word.end(), [](char c) { return c >= 'a' && c <= 'z'; });
}

// Rows of `rows` scaled to unit length; zero rows stay zero.
void normalize_rows(RowMatrix& rows) {
  for (Eigen::Index i = 0; i < rows.rows(); ++i) {
    const float norm = rows.row(i).norm();
    if (norm > 0) rows.row(i) /= norm;
  }
}

}  // namespace

void SynonymOptions::validate() const {
  if (per_word < 1) throw std::invalid_argument("per_word must be >= 1");
  if (!(min_cosine > -1 && min_cosine < 1)) throw std::invalid_argument("min_cosine must be in (-1, 1)");
}

SynonymTable SynonymTable::build(const WordVectors& vectors, const std::vector<std::string>& caption_words,
                                 const SynonymOptions& options) {
  options.validate();
  const std::set<std::string> caption_set(caption_words.begin(), caption_words.end());
  std::vector<std::string> words;  // caption words with a vector
  std::vector<size_t> word_rows;
  for (const std::string& word : caption_set) {
    if (const std::optional<size_t> row = vectors.index_of(word)) {
      words.push_back(word);
      word_rows.push_back(*row);
    }
  }
  SynonymTable table;
  if (words.empty() || vectors.size() == 0) return table;
  const int dim = vectors.dim();
  RowMatrix captions(static_cast<Eigen::Index>(words.size()), dim);
  for (size_t i = 0; i < words.size(); ++i) {
    captions.row(static_cast<Eigen::Index>(i)) =
        Eigen::Map<const Eigen::RowVectorXf>(vectors.vector_data(word_rows[i]), dim);
  }
  normalize_rows(captions);

  // Candidates of each caption word: (cosine, vector row) of the words closest to it.
  std::vector<std::vector<std::pair<float, size_t>>> candidates(words.size());
  const size_t total = vectors.size();
  constexpr size_t kChunk = 8192;  // rows scored at once: a chunk x caption words matrix stays small
  for (size_t start = 0; start < total; start += kChunk) {
    const size_t count = std::min(kChunk, total - start);
    RowMatrix chunk = Eigen::Map<const RowMatrix>(vectors.vector_data(start), static_cast<Eigen::Index>(count), dim);
    normalize_rows(chunk);
    const RowMatrix cosines = chunk * captions.transpose();  // (count, caption words)
    for (size_t r = 0; r < count; ++r) {
      Eigen::Index closest = 0;
      const float best = cosines.row(static_cast<Eigen::Index>(r)).maxCoeff(&closest);
      if (best < options.min_cosine) continue;
      const std::string_view word = vectors.word(start + r);
      if (!lower_letters_only(word) || caption_set.count(std::string(word)) > 0) continue;
      candidates[static_cast<size_t>(closest)].emplace_back(best, start + r);
    }
  }
  for (size_t i = 0; i < words.size(); ++i) {
    auto& found = candidates[i];
    if (found.empty()) continue;
    // Closest first; equal cosines in vocabulary order so that the table never depends on the sort.
    std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    found.resize(std::min(found.size(), static_cast<size_t>(options.per_word)));
    std::vector<std::string>& synonyms = table.synonyms_[words[i]];
    for (const auto& [cosine, row] : found) synonyms.emplace_back(vectors.word(row));
  }
  return table;
}

const std::vector<std::string>& SynonymTable::synonyms_of(const std::string& word) const {
  static const std::vector<std::string> none;
  const auto found = synonyms_.find(word);
  return found == synonyms_.end() ? none : found->second;
}

size_t SynonymTable::synonym_count() const {
  size_t count = 0;
  for (const auto& [word, synonyms] : synonyms_) count += synonyms.size();
  return count;
}

std::string SynonymTable::rewrite(std::string_view normalized, double probability, SplitMix64& random) const {
  std::string out;
  for (const std::string& word : caption_words(normalized)) {
    const std::vector<std::string>& synonyms = synonyms_of(word);
    // Every word draws once whatever it is, so one caption's draws never shift the next caption's.
    const bool replace = random.chance(probability);
    const uint64_t pick = random.next();
    out += out.empty() ? "" : " ";
    out += replace && !synonyms.empty() ? synonyms[pick % synonyms.size()] : word;
  }
  return out;
}

}  // namespace nec::text

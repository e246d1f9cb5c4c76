// Caption pieces (DESIGN.md, Text): a sentencepiece model trained on the
// corpus captions. libsentencepiece is reached only through nec_spm_bridge
// (text/spm/bridge.h), opened here with dlopen(RTLD_NOW | RTLD_LOCAL |
// RTLD_DEEPBIND): its bundled protobuf crashes a process that links libtorch
// when it is linked the usual way.
//
//   PieceTrainOptions options;                               // BPE, at most 1000 pieces
//   train_piece_model({"a dog trots forward", ...}, options, "spm.model");  // normalized captions
//   const PieceModel model = PieceModel::load("spm.model");
//   std::vector<int> ids = model.encode("a dog trots forward");              // e.g. {57, 12, 301, 44}
//   std::string back = model.decode(ids);                                    // "a dog trots forward"
//
// Ids: 0 pad, 1 unknown, then the pieces. A piece that starts a word begins
// with "▁" (U+2581), e.g. "▁dog", "▁scut" "tles".
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace nec::text {

inline constexpr int kPadPiece = 0;
inline constexpr int kUnknownPiece = 1;

struct PieceTrainOptions {
  // Most pieces (pad and unknown included); fewer when the captions hold fewer.
  // 1000 BPE pieces keep every word of the README corpus's captions whole and
  // leave the rest for parts of words no caption used (docs/text.md).
  int vocab_size = 1000;
  std::string model_type = "bpe";  // or "unigram", "word", "char"
  int threads = 1;                     // sentencepiece's trainer threads; 1: the same model on every run

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

// Trains on `sentences` (each one line; run normalize_caption first) and writes
// the model to `out_path` atomically. Throws InputError(out_path, ...) when
// sentencepiece refuses (e.g. no sentences) and std::runtime_error when the
// bridge library cannot be opened.
// A caption cut into pieces, each knowing the word it belongs to (what the
// text encoder reads: a word's vector goes with each of its pieces).
struct CaptionPieces {
  std::vector<int> ids;            // (P) piece ids
  std::vector<int> word_of_piece;  // (P) index into words
  std::vector<std::string> words;  // the caption's words in order, e.g. {"a", "dog", "scuttles"}
};

void train_piece_model(const std::vector<std::string>& sentences, const PieceTrainOptions& options,
                       const std::string& out_path);

class PieceModel {
 public:
  // Throws InputError(path, ...) for a missing or damaged model file.
  static PieceModel load(const std::string& path);
  PieceModel(PieceModel&&) noexcept;
  PieceModel& operator=(PieceModel&&) noexcept;
  ~PieceModel();

  int vocab_size() const { return vocab_size_; }
  const std::string& path() const { return path_; }
  // The piece ids of `text` as it is (normalize it first).
  std::vector<int> encode(std::string_view text) const;
  // The text of `ids`; throws std::invalid_argument for an id outside the vocabulary.
  std::string decode(const std::vector<int>& ids) const;
  // The piece's bytes, e.g. "▁dog"; throws std::invalid_argument outside the vocabulary.
  const std::string& piece(int id) const;
  // The piece begins a word (its bytes start with "▁").
  bool starts_word(int id) const;
  // The piece without its word-start mark, e.g. "▁dog" -> "dog", "tles" -> "tles".
  std::string piece_text(int id) const;
  // encode(normalized) with the word of every piece: a word starts at each
  // piece that starts_word (or at the first piece). The words are the
  // caption's own (caption_words) when the counts agree, else the pieces'
  // texts joined, an unknown piece adding nothing.
  CaptionPieces split(std::string_view normalized) const;

 private:
  struct Handle;
  PieceModel() = default;
  void check(int id) const;
  std::unique_ptr<Handle> handle_;
  std::string path_;
  int vocab_size_ = 0;
  std::vector<std::string> pieces_;
};

}  // namespace nec::text

// Word vectors (DESIGN.md, Text): GloVe 6B 100-d, imported once by
// `nec text import-glove` into a compact binary file that loads in milliseconds
// (memory-mapped), and joint-name embeddings built from them.
//
//   const auto vectors = nec::text::WordVectors::load(nec::text::default_word_vectors_path());
//   nec::text::Vector thigh = vectors.embed_joint_name("thigh.L");     // (dim), mean of "left" "upper" "leg"
//   nec::text::Vector hip = vectors.embed_joint_name("LeftUpLeg");
//   float similarity = nec::text::cosine_similarity(thigh, hip);       // 1: both are "left upper leg"
//
// File format (little-endian, version 1), written atomically by write_word_vectors:
//   header, 64 bytes:
//     0  char[8]  magic "NECWVEC\0"
//     8  u32      format version (kWordVectorFormatVersion)
//    12  u32      dim, e.g. 100
//    16  u64      word count N, e.g. 341479
//    24  u64      word bytes W: total UTF-8 bytes of all words
//    32  u64      vectors offset V: start of the vectors, a multiple of 64
//    40  24 bytes zero
//   64            u32 offsets[N + 1]: word i is bytes [offsets[i], offsets[i+1]) of the word bytes
//   64 + 4(N+1)   word bytes (W), words sorted by bytes, no duplicates, no terminators
//   ...           zero padding up to V
//   V             float32 vectors (N, dim), row i belongs to word i
// The file size is exactly V + 4 * N * dim; anything else is "truncated".
#pragma once

#include "nec/motion/files.h"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace nec::text {

using Vector = std::vector<float>;  // (dim)

inline constexpr char kWordVectorMagic[8] = {'N', 'E', 'C', 'W', 'V', 'E', 'C', '\0'};
inline constexpr uint32_t kWordVectorFormatVersion = 1;
inline constexpr size_t kWordVectorHeaderBytes = 64;
// What every "cannot use the word vectors" message ends with.
inline constexpr const char* kWordVectorHint =
    "run: scripts/setup_glove.sh && nec text import-glove  (or pass --glove FILE)";

// Where commands look for the imported vectors when no --glove is given:
// $NEC_HOME/glove-100d.bin when NEC_HOME is set, else
// <repository>/third_party_cache/glove-100d.bin (the repository nec was built from).
std::string default_word_vectors_path();

// The words of a joint name's canonical form, nec::canonical_joint_name split
// on spaces: "LeftUpLeg" -> {"left", "upper", "leg"}; may be empty.
std::vector<std::string> canonical_words(std::string_view joint_name);

// The stand-in vector of a word that is not in the vocabulary: unit norm and a
// pure function of the word's bytes and dim, the same on every platform:
// u_i = uniform in [-1, 1) from splitmix64 seeded with FNV-1a-64(word), then
// u / |u|. Different words get (almost surely) different, near-orthogonal vectors.
Vector fallback_vector(std::string_view word, int dim);

// Cosine of the angle between a and b (same size); 0 when either is zero.
float cosine_similarity(const Vector& a, const Vector& b);

struct Neighbour {
  std::string word;
  float cosine = 0;
};

class WordVectors {
 public:
  // Maps a file written by write_word_vectors. A missing file, bad magic, an
  // unknown version, truncation or inconsistent offsets throw nec::InputError
  // naming the file and ending with kWordVectorHint.
  static WordVectors load(const std::string& path);
  // load(path, or default_word_vectors_path() when empty), checked to hold
  // `dim`-d vectors (the width of the names a model reads): InputError naming
  // the file and both widths otherwise.
  static WordVectors load_checked(const std::string& path, int64_t dim);

  WordVectors(WordVectors&& other) noexcept = default;
  WordVectors& operator=(WordVectors&& other) noexcept = default;
  WordVectors(const WordVectors&) = delete;
  WordVectors& operator=(const WordVectors&) = delete;
  ~WordVectors() = default;

  int dim() const { return dim_; }
  size_t size() const { return word_count_; }
  const std::string& path() const { return path_; }

  // Exact, case-sensitive lookup (the GloVe vocabulary is lower case).
  std::optional<size_t> index_of(std::string_view word) const;
  std::string_view word(size_t index) const;                  // index < size()
  const float* vector_data(size_t index) const;               // (dim), index < size()
  std::optional<Vector> lookup(std::string_view word) const;  // a copy of the stored float32 vector

  // Mean of the vectors of the known words (ASCII letters lower-cased first);
  // unknown words are left out of the mean and listed in *unknown when given.
  // When no word is known (or `words` is empty) the result is
  // fallback_vector(words joined by single spaces).
  Vector embed_words(const std::vector<std::string>& words, std::vector<std::string>* unknown = nullptr) const;
  // embed_words(canonical_words(joint_name)).
  Vector embed_joint_name(std::string_view joint_name, std::vector<std::string>* unknown = nullptr) const;

  // The `count` vocabulary words with the highest cosine to `query`, best
  // first, leaving out the words in `exclude`. A full scan: about 30 ms for 341k words.
  std::vector<Neighbour> nearest(const Vector& query, int count, const std::vector<std::string>& exclude = {}) const;

 private:
  WordVectors() = default;

  std::string path_;
  MappedFile file_;  // the whole file, read-only
  int dim_ = 0;
  size_t word_count_ = 0;
  const uint32_t* offsets_ = nullptr;  // (N + 1)
  const char* word_bytes_ = nullptr;   // (W)
  const float* vectors_ = nullptr;     // (N, dim)
};

// Writes `words` (any order, unique) with their vectors (N, dim) to `path` in the
// format above: sorted, to a temporary file next to it, then renamed, so a
// failure leaves no half-written file. Returns the bytes written. Duplicate
// words or a size mismatch throw std::invalid_argument; I/O errors nec::InputError.
uint64_t write_word_vectors(const std::string& path, const std::vector<std::string>& words,
                            const std::vector<float>& vectors, int dim);

}  // namespace nec::text

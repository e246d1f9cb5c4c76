// The word-vector file: writing (sorted, atomic), memory-mapped loading with
// validation, lookups, fallback vectors, joint-name embeddings, nearest words.
#include "nec/text/word_vectors.h"

#include "nec/text/caption_text.h"
#include "nec/text/fetched_data.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/hash.h"
#include "nec/motion/names.h"
#include "nec/motion/random.h"


#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <queue>
#include <stdexcept>
#include <utility>

namespace nec::text {
namespace {

bool host_is_little_endian() {
  const uint32_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

template <typename T>
T read_field(const unsigned char* bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes + offset, sizeof(T));
  return value;
}

template <typename T>
void write_field(unsigned char* bytes, size_t offset, T value) {
  std::memcpy(bytes + offset, &value, sizeof(T));
}

size_t round_up_64(size_t value) { return (value + 63) / 64 * 64; }

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw InputError(path, 0, problem + "; " + kWordVectorHint);
}

std::string ascii_lower(std::string_view word) {
  std::string out(word);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

double norm_of(const float* v, int dim) {
  double sum = 0;
  for (int i = 0; i < dim; ++i) sum += static_cast<double>(v[i]) * v[i];
  return std::sqrt(sum);
}

}  // namespace

std::string default_word_vectors_path() { return fetched_data_path("glove-100d.bin"); }

std::vector<std::string> canonical_words(std::string_view joint_name) {
  return caption_words(canonical_joint_name(joint_name));
}

Vector fallback_vector(std::string_view word, int dim) {
  Vector v(static_cast<size_t>(std::max(dim, 0)));
  if (v.empty()) return v;
  SplitMix64 random(fnv1a64(word));
  double sum = 0;
  for (float& x : v) {
    // 24 random bits -> a float in [-1, 1), exact.
    x = static_cast<float>(static_cast<int32_t>(random.next() >> 40) - (1 << 23)) / static_cast<float>(1 << 23);
    sum += static_cast<double>(x) * x;
  }
  if (sum == 0) {
    v[0] = 1;
    return v;
  }
  const double inverse_norm = 1.0 / std::sqrt(sum);
  for (float& x : v) x = static_cast<float>(x * inverse_norm);
  return v;
}

float cosine_similarity(const Vector& a, const Vector& b) {
  if (a.size() != b.size()) throw std::invalid_argument("cosine_similarity: vectors of different sizes");
  double dot = 0, aa = 0, bb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    dot += static_cast<double>(a[i]) * b[i];
    aa += static_cast<double>(a[i]) * a[i];
    bb += static_cast<double>(b[i]) * b[i];
  }
  if (aa == 0 || bb == 0) return 0;
  return static_cast<float>(dot / std::sqrt(aa * bb));
}

WordVectors WordVectors::load_checked(const std::string& path, int64_t dim) {
  WordVectors vectors = load(path.empty() ? default_word_vectors_path() : path);
  if (vectors.dim() != dim) {
    throw InputError(vectors.path(), 0,
                     "holds " + std::to_string(vectors.dim()) + "-d vectors, but the model reads " +
                         std::to_string(dim) + "-d names; pass the --glove file it was trained with");
  }
  return vectors;
}

WordVectors WordVectors::load(const std::string& path) {
  if (!host_is_little_endian()) fail(path, "word-vector files are little-endian and this machine is not");
  WordVectors result;
  result.path_ = path;
  try {
    result.file_ = MappedFile::open(path);
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + "; " + kWordVectorHint);
  }
  const size_t file_bytes = result.file_.size();
  if (file_bytes < kWordVectorHeaderBytes) {
    fail(path, "truncated: " + std::to_string(file_bytes) + " bytes, shorter than the 64-byte header");
  }
  const unsigned char* bytes = result.file_.data();

  if (std::memcmp(bytes, kWordVectorMagic, sizeof kWordVectorMagic) != 0)
    fail(path, "not a nec word-vector file (bad magic)");
  const auto version = read_field<uint32_t>(bytes, 8);
  if (version != kWordVectorFormatVersion)
    fail(path, "word-vector format version " + std::to_string(version) + ", this nec reads version " +
                   std::to_string(kWordVectorFormatVersion));
  const auto dim = read_field<uint32_t>(bytes, 12);
  const auto word_count = read_field<uint64_t>(bytes, 16);
  const auto word_bytes = read_field<uint64_t>(bytes, 24);
  const auto vectors_offset = read_field<uint64_t>(bytes, 32);
  if (dim == 0 || dim > 65536) fail(path, "implausible dimension " + std::to_string(dim));
  // Every size is checked against the file before it is multiplied, so nothing overflows.
  if (word_count > file_bytes / 4 || word_bytes > file_bytes)
    fail(path, "truncated or corrupt: header claims " + std::to_string(word_count) + " words and " +
                   std::to_string(word_bytes) + " word bytes in a " + std::to_string(file_bytes) + "-byte file");
  const uint64_t words_end = kWordVectorHeaderBytes + 4 * (word_count + 1) + word_bytes;
  if (vectors_offset != round_up_64(words_end)) fail(path, "corrupt header (vectors offset)");
  if (word_count > (file_bytes / 4) / dim)
    fail(path, "truncated: " + std::to_string(file_bytes) + " bytes cannot hold " + std::to_string(word_count) +
                   " vectors of " + std::to_string(dim));
  const uint64_t expected_bytes = vectors_offset + 4 * word_count * dim;
  if (file_bytes != expected_bytes)
    fail(path, (file_bytes < expected_bytes ? "truncated: " : "trailing bytes: ") + std::to_string(file_bytes) +
                   " bytes, expected " + std::to_string(expected_bytes));

  result.dim_ = static_cast<int>(dim);
  result.word_count_ = word_count;
  result.offsets_ = reinterpret_cast<const uint32_t*>(bytes + kWordVectorHeaderBytes);
  result.word_bytes_ = reinterpret_cast<const char*>(bytes + kWordVectorHeaderBytes + 4 * (word_count + 1));
  result.vectors_ = reinterpret_cast<const float*>(bytes + vectors_offset);
  // Offsets must rise to word_bytes and words must be strictly sorted, or binary search lies.
  if (result.offsets_[0] != 0 || result.offsets_[word_count] != word_bytes)
    fail(path, "corrupt word offsets");
  for (size_t i = 0; i < word_count; ++i) {
    if (result.offsets_[i + 1] < result.offsets_[i]) fail(path, "corrupt word offsets");
    if (i > 0 && !(result.word(i - 1) < result.word(i)))
      fail(path, "words are not strictly sorted at word " + std::to_string(i));
  }
  return result;
}

std::string_view WordVectors::word(size_t index) const {
  return {word_bytes_ + offsets_[index], static_cast<size_t>(offsets_[index + 1] - offsets_[index])};
}

const float* WordVectors::vector_data(size_t index) const { return vectors_ + index * static_cast<size_t>(dim_); }

std::optional<size_t> WordVectors::index_of(std::string_view word_to_find) const {
  size_t low = 0, high = word_count_;
  while (low < high) {
    const size_t middle = low + (high - low) / 2;
    if (word(middle) < word_to_find)
      low = middle + 1;
    else
      high = middle;
  }
  if (low < word_count_ && word(low) == word_to_find) return low;
  return std::nullopt;
}

std::optional<Vector> WordVectors::lookup(std::string_view word_to_find) const {
  const auto index = index_of(word_to_find);
  if (!index) return std::nullopt;
  const float* v = vector_data(*index);
  return Vector(v, v + dim_);
}

Vector WordVectors::embed_words(const std::vector<std::string>& words, std::vector<std::string>* unknown) const {
  std::vector<double> sum(static_cast<size_t>(dim_), 0.0);
  int known = 0;
  for (const std::string& original : words) {
    const auto index = index_of(ascii_lower(original));
    if (!index) {
      if (unknown != nullptr) unknown->push_back(original);
      continue;
    }
    const float* v = vector_data(*index);
    for (int i = 0; i < dim_; ++i) sum[static_cast<size_t>(i)] += v[i];
    ++known;
  }
  if (known == 0) {
    std::string joined;
    for (const std::string& w : words) joined += (joined.empty() ? "" : " ") + ascii_lower(w);
    return fallback_vector(joined, dim_);
  }
  Vector mean(static_cast<size_t>(dim_));
  for (int i = 0; i < dim_; ++i) mean[static_cast<size_t>(i)] = static_cast<float>(sum[static_cast<size_t>(i)] / known);
  return mean;
}

Vector WordVectors::embed_joint_name(std::string_view joint_name, std::vector<std::string>* unknown) const {
  return embed_words(canonical_words(joint_name), unknown);
}

std::vector<Neighbour> WordVectors::nearest(const Vector& query, int count, const std::vector<std::string>& exclude) const {
  if (query.size() != static_cast<size_t>(dim_)) throw std::invalid_argument("nearest: query has the wrong size");
  std::vector<Neighbour> result;
  const double query_norm = norm_of(query.data(), dim_);
  if (count <= 0 || query_norm == 0) return result;
  std::vector<std::string> excluded;
  for (const std::string& w : exclude) excluded.push_back(ascii_lower(w));
  using Scored = std::pair<float, size_t>;  // (cosine, index); the heap keeps the worst on top
  std::priority_queue<Scored, std::vector<Scored>, std::greater<Scored>> best;
  for (size_t index = 0; index < word_count_; ++index) {
    const float* v = vector_data(index);
    float dot = 0, squared = 0;
    for (int i = 0; i < dim_; ++i) {
      dot += v[i] * query[static_cast<size_t>(i)];
      squared += v[i] * v[i];
    }
    if (squared == 0) continue;
    const float cosine = static_cast<float>(dot / (std::sqrt(squared) * query_norm));
    if (best.size() == static_cast<size_t>(count) && cosine <= best.top().first) continue;
    if (std::find(excluded.begin(), excluded.end(), word(index)) != excluded.end()) continue;
    best.emplace(cosine, index);
    if (best.size() > static_cast<size_t>(count)) best.pop();
  }
  while (!best.empty()) {
    result.push_back({std::string(word(best.top().second)), best.top().first});
    best.pop();
  }
  std::reverse(result.begin(), result.end());
  return result;
}

uint64_t write_word_vectors(const std::string& path, const std::vector<std::string>& words,
                            const std::vector<float>& vectors, int dim) {
  if (dim <= 0) throw std::invalid_argument("write_word_vectors: dim must be positive");
  if (vectors.size() != words.size() * static_cast<size_t>(dim))
    throw std::invalid_argument("write_word_vectors: " + std::to_string(vectors.size()) + " floats for " +
                                std::to_string(words.size()) + " words of dim " + std::to_string(dim));
  std::vector<size_t> order(words.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return words[a] < words[b]; });
  uint64_t word_bytes = 0;
  for (size_t i = 0; i < order.size(); ++i) {
    if (i > 0 && words[order[i - 1]] == words[order[i]])
      throw std::invalid_argument("write_word_vectors: duplicate word '" + words[order[i]] + "'");
    word_bytes += words[order[i]].size();
  }
  if (word_bytes > UINT32_MAX) throw std::invalid_argument("write_word_vectors: more than 4 GiB of words");

  const uint64_t words_end = kWordVectorHeaderBytes + 4 * (words.size() + 1) + word_bytes;
  const uint64_t vectors_offset = round_up_64(words_end);
  std::vector<unsigned char> head(vectors_offset, 0);
  std::memcpy(head.data(), kWordVectorMagic, sizeof kWordVectorMagic);
  write_field<uint32_t>(head.data(), 8, kWordVectorFormatVersion);
  write_field<uint32_t>(head.data(), 12, static_cast<uint32_t>(dim));
  write_field<uint64_t>(head.data(), 16, words.size());
  write_field<uint64_t>(head.data(), 24, word_bytes);
  write_field<uint64_t>(head.data(), 32, vectors_offset);
  size_t offset_at = kWordVectorHeaderBytes;
  size_t byte_at = kWordVectorHeaderBytes + 4 * (words.size() + 1);
  uint32_t offset = 0;
  write_field<uint32_t>(head.data(), offset_at, 0);
  for (const size_t index : order) {
    std::memcpy(head.data() + byte_at, words[index].data(), words[index].size());
    byte_at += words[index].size();
    offset += static_cast<uint32_t>(words[index].size());
    offset_at += 4;
    write_field<uint32_t>(head.data(), offset_at, offset);
  }

  const std::filesystem::path target(path);
  if (target.has_parent_path()) {
    std::error_code ignored;
    std::filesystem::create_directories(target.parent_path(), ignored);
  }
  std::string contents(head.begin(), head.end());
  contents.reserve(head.size() + order.size() * static_cast<size_t>(dim) * sizeof(float));
  for (const size_t index : order) {
    contents.append(reinterpret_cast<const char*>(vectors.data() + index * static_cast<size_t>(dim)),
                    static_cast<size_t>(dim) * sizeof(float));
  }
  try {
    write_file_atomic(path, contents);
  } catch (const std::runtime_error& e) {
    throw InputError(path, 0, e.what());
  }
  return vectors_offset + 4 * static_cast<uint64_t>(words.size()) * static_cast<uint64_t>(dim);
}

}  // namespace nec::text

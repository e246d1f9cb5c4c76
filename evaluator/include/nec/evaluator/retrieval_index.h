// The retrieval index of a dataset cache: every clip's motion embedding and
// every distinct caption's text embedding under one evaluator, computed once
// and stored in the cache directory. `nec retrieve` reads it.
//
//   RetrievalIndex index = open_retrieval_index(session, cache, "runs/eval/best");  // built on first use
//   std::vector<Match> top = index.nearest_clips(session.embed_captions({"a dog trots"}, "query"), 5, {});
//
// The file, cache/retrieval-<evaluator key>.index, is keyed by the cache (a
// hash of its manifest) and the evaluator (a hash of its config and tensors):
// a rewritten cache is a new directory without it, another evaluator has
// another key, and a stale or damaged file is rebuilt. Written atomically
// (temp file + rename). When the cache directory is read-only the index is
// kept in memory only (the caller is told).
//
// Format (little-endian, version 1): "NECRIDX\0", u32 version, u32 dim D,
// u64 cache key, u64 evaluator key, u64 clips N, u64 captions M; N u32 clip
// indices; N x D float32 motion embeddings; M captions as u32 length + bytes;
// M x D float32 text embeddings.
#pragma once

#include "nec/evaluator/evaluator.h"
#include "nec/corpus/dataset.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace nec::evaluator {

inline constexpr uint32_t kRetrievalIndexVersion = 1;

struct Match {
  int row = 0;        // row of the index: a clip (nearest_clips) or a caption (nearest_captions)
  float score = 0.f;  // cosine similarity
};

struct RetrievalIndex {
  uint64_t cache_key = 0;
  uint64_t evaluator_key = 0;
  int dim = 0;
  std::vector<int> clips;              // (N) clip indices into the cache
  std::vector<float> clip_embeddings;  // (N, D) unit length
  std::vector<std::string> captions;   // (M) every distinct caption of the cache's clips
  std::vector<float> caption_embeddings;  // (M, D) unit length

  // The k best clips for a (1, D) query, best first, among those `keep` accepts (all when empty).
  std::vector<Match> nearest_clips(const at::Tensor& query, int k, const std::function<bool(int clip)>& keep) const;
  // The k best captions for a (1, D) query, best first.
  std::vector<Match> nearest_captions(const at::Tensor& query, int k) const;
};

// The evaluator's key is train::checkpoint_key of its directory, the cache's nec::cache_key.
std::string retrieval_index_path(const DatasetCache& cache, uint64_t evaluator_key);

// Embeds every clip and distinct caption of `cache`.
RetrievalIndex build_retrieval_index(EvaluatorSession& session, const DatasetCache& cache, uint64_t evaluator_key);
// The index file's bytes, and back (InputError naming `path` for a damaged file).
std::string serialize(const RetrievalIndex& index);
RetrievalIndex deserialize_retrieval_index(const std::string& bytes, const std::string& path);

struct OpenedIndex {
  RetrievalIndex index;
  bool built = false;   // embedded now (no usable file)
  bool stored = false;  // written to the cache directory now
  std::string path;
  std::string note;     // why it was rebuilt or not stored, for the user
};
// The stored index when its keys match, else a new one (stored when possible).
OpenedIndex open_retrieval_index(EvaluatorSession& session, const DatasetCache& cache, const std::string& evaluator_dir);

}  // namespace nec::evaluator

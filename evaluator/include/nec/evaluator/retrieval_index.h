// The retrieval index of a dataset cache: every clip's motion embedding and
// every distinct caption's text embedding under one evaluator, computed once
// and stored in the cache directory. `nec retrieve` reads it. Beside them, each
// caption's vector from the pretrained sentence encoder (text/sentence_encoder.h)
// and which captions each clip has, so that a query can also be matched with
// the database's own caption texts (CaptionBlend).
//
//   RetrievalIndex index = open_retrieval_index(session, cache, "runs/eval/best");  // built on first use
//   std::vector<Match> top = index.nearest_clips(session.embed_captions({"a dog trots"}, "query"), 5, {});
//   CaptionBlend blend{caption_text_vectors({"a dog trots"}, "query"), 0.5f};
//   std::vector<Match> mixed = index.nearest_clips(session.embed_captions({"a dog trots"}, "query"), 5, {}, blend);
//
// The file, cache/retrieval-<evaluator key>.index, is keyed by the cache (a
// hash of its manifest) and the evaluator (a hash of its config and tensors):
// a rewritten cache is a new directory without it, another evaluator has
// another key, and a stale or damaged file is rebuilt. Written atomically
// (temp file + rename). When the cache directory is read-only the index is
// kept in memory only (the caller is told).
//
// Format (little-endian, version 2): "NECRIDX\0", u32 version, u32 dim D,
// u64 cache key, u64 evaluator key, u64 clips N, u64 captions M; N u32 clip
// indices; N x D float32 motion embeddings; M captions as u32 length + bytes;
// M x D float32 text embeddings; u32 sentence width T; M x T float32 sentence
// vectors; per clip a u32 count and that many u32 caption rows.
#pragma once

#include "nec/evaluator/evaluator.h"
#include "nec/corpus/dataset.h"

#include <ATen/core/Tensor.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace nec::evaluator {

inline constexpr uint32_t kRetrievalIndexVersion = 2;

struct Match {
  int row = 0;        // row of the index: a clip (nearest_clips) or a caption (nearest_captions)
  float score = 0.f;  // cosine similarity; with a CaptionBlend, the blend of the standardized scores
};

// A caption query matched with the database's own caption texts as well as with the motions: `text` is the
// query's sentence vector (1, T) (caption_text_vectors), `weight` in [0, 1] how much the nearest of a clip's
// captions counts against the motion embedding (0: the motion alone). Each score is standardized over the
// clips searched (mean 0, deviation 1) before they are mixed, so that the weight means the same whatever the
// evaluator's cosines spread; a clip without captions is ranked by its motion alone.
struct CaptionBlend {
  at::Tensor text;
  float weight = 0.f;
};

struct RetrievalIndex {
  uint64_t cache_key = 0;
  uint64_t evaluator_key = 0;
  int dim = 0;
  std::vector<int> clips;              // (N) clip indices into the cache
  std::vector<float> clip_embeddings;  // (N, D) unit length
  std::vector<std::string> captions;   // (M) every distinct caption of the cache's clips
  std::vector<float> caption_embeddings;  // (M, D) unit length
  int text_dim = 0;                       // T
  std::vector<float> caption_texts;       // (M, T) the sentence encoder's unit vectors of the captions
  std::vector<std::vector<int>> clip_captions;  // (N) rows of `captions` each clip has

  // The k best clips for a (1, D) query, best first, among those `keep` accepts (all when empty).
  std::vector<Match> nearest_clips(const at::Tensor& query, int k, const std::function<bool(int clip)>& keep,
                                   const CaptionBlend& blend = {}) const;
  // The k best captions for a (1, D) query, best first.
  std::vector<Match> nearest_captions(const at::Tensor& query, int k) const;
};

// (N, T) unit vectors of the pretrained sentence encoder for normalized, checked captions (InputError naming
// `where`): what CaptionBlend compares.
at::Tensor caption_text_vectors(const std::vector<std::string>& captions, const std::string& where);

// The evaluator's key is train::checkpoint_key of its directory, the cache's nec::cache_key.
std::string retrieval_index_path(const DatasetCache& cache, uint64_t evaluator_key);

// Embeds every clip and distinct caption of `cache` (captions by the evaluator and by the sentence encoder).
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

// Using a trained tokenizer on whole clips of any length: joint embeddings of
// skeletons from the frozen OwO encoder, and windowed encode / decode.
//
//   at::Tensor h = embed_skeletons(*owo->encoder, {skeleton}, {canonical_names}, &vectors)[0];  // (J, D)
//   at::Tensor codes = encode_clip(*tokenizer, features, h, WindowOptions{64, 16});  // (S, R)
//   Features back = decode_clip(*tokenizer, codes, features.frame_count, target_h, target_skeleton, 30, {64, 16});
//
// Windows: clips longer than window_frames are cut into windows that overlap
// by overlap_frames (every window is encoded like a training crop: its frame 0
// holds the absolute root height). Each token step is taken from the window
// where it sits farthest from an edge. Decoding cuts the token sequence into
// the same windows, decodes them together, and cross-fades the overlaps
// linearly (rot6D, horizontal root displacement and absolute root height), so
// the seams do not jump. Clips up to one window are a single window (padded to
// a multiple of the downsampling by holding the last pose).
#pragma once

#include "nec/corpus/batch.h"
#include "nec/corpus/dataset.h"
#include "nec/motion/features.h"
#include "nec/owo/encoder.h"
#include "nec/tat/tokenizer.h"
#include "nec/text/word_vectors.h"

#include <ATen/core/Tensor.h>

#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

namespace nec::tat {

// (B, Jmax, D) OwO joint embeddings of the skeletons (normalized, with their
// canonical names), zero at padding; no gradient. `vectors` may be null only
// when the encoder was trained without names (name_dim = 0); otherwise
// InputError with text::kWordVectorHint.
at::Tensor embed_skeletons(owo::OwoEncoderImpl& encoder, const std::vector<Skeleton>& skeletons,
                           const std::vector<std::vector<std::string>>& canonical_names,
                           const text::WordVectors* vectors);
// All of the encoder's outputs for the same input: the joints as above and the skeleton node (B, D).
owo::OwoOutput encode_skeletons(owo::OwoEncoderImpl& encoder, const std::vector<Skeleton>& skeletons,
                                const std::vector<std::vector<std::string>>& canonical_names,
                                const text::WordVectors* vectors);

// embed_skeletons for trainers whose OwO encoder is frozen: every step embeds
// its batch's skeletons, and the corpus's own rigs come back step after step
// (the OwO was up to a quarter of an evaluator step). The rigs of the train
// and val clips of a cache are embedded once, smallest first in chunks of
// bounded items × joints², and kept (as many as max_bytes holds: the largest
// rigs are the ones left out); other rigs (those a batch
// augmented) are embedded as they come. Kept once, before the first step, a
// rig reads the same at every step and in a resumed run. The numbers differ
// from embedding a batch afresh by float rounding (products of other shapes).
class RememberedSkeletonEmbeddings {
 public:
  RememberedSkeletonEmbeddings(owo::OwoEncoder encoder, const text::WordVectors* vectors, const DatasetCache& cache,
                               size_t max_bytes);
  ~RememberedSkeletonEmbeddings();

  // (B, Jmax, D) joint embeddings of the batch's skeletons, zero at padding;
  // no gradient (a tensor autograd may read, unlike an inference one).
  at::Tensor embed(const Batch& batch);
  size_t kept_rigs() const { return kept_.size(); }

 private:
  owo::OwoEncoder encoder_;
  const text::WordVectors* vectors_;
  std::unordered_map<std::string, at::Tensor> kept_;  // (J, D) by skeleton_key
};

struct WindowOptions {
  int64_t window_frames = 64;   // frames per window, e.g. the training crop; a multiple of the downsampling
  int64_t overlap_frames = 16;  // frames shared by neighbouring windows; a multiple of 2 x downsampling, < window

  // Throws std::invalid_argument naming the bad field for a model with downsampling r.
  void validate(int64_t downsampling) const;
};

// Token codes (S, R) int64 of a clip's Θ, S = ceil(T / r). `embeddings` (J, D)
// for the clip's skeleton (undefined for the zero-padding baseline).
at::Tensor encode_clip(TokenizerImpl& tokenizer, const Features& features, const at::Tensor& embeddings,
                       const WindowOptions& windows);

// Θ (frame_count, J, 9) decoded from codes (S, R) for a normalized skeleton with
// `embeddings` (J, D) (undefined for the baseline), its body facing +Z at
// frame 0 (face_forward_at_start); start_xz = (0, 0).
Features decode_clip(TokenizerImpl& tokenizer, const at::Tensor& codes, int frame_count, const at::Tensor& embeddings,
                     const Skeleton& skeleton, double fps, const WindowOptions& windows);

}  // namespace nec::tat

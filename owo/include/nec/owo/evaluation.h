// How well a pretrained OwO model knows skeletons: per skeleton, the LCA
// pointer's accuracy over all joint pairs, the error of the predicted rest
// offsets, and whether the whole tree is rebuilt from the predicted LCAs
// (NECromancer appendix C.4, tree_rebuild.h), two ways: exactly from the
// predicted LCA matrix (rebuild_tree; the matrix is the model's argmax for
// every pair i != j, its diagonal LCA(i, i) = i by definition, which C.4
// never asks for), and as the tree that best agrees with the predicted LCA
// probabilities (decode_tree). Either counts only when its parent array is
// the true one; the true tree is read for nothing else.
//
//   std::vector<SkeletonScore> scores = score_skeletons(*model, set.held_out, &vectors, torch::kCPU);
//   ScoreSummary all = summarize(scores);   // all.rebuild_rate, all.decode_rate, all.lca_accuracy ...
#pragma once

#include "nec/owo/pretrain.h"
#include "nec/owo/skeleton_set.h"
#include "nec/text/word_vectors.h"

#include <c10/core/Device.h>

#include <cstdint>
#include <string>
#include <vector>

namespace nec::owo {

struct SkeletonScore {
  std::string name;            // PretrainSkeleton::name, e.g. "zoo_held-3"
  std::string group;           // PretrainSkeleton::group, e.g. "spider"
  int joints = 0;              // J
  int64_t pairs = 0;           // unordered pairs i < j scored: J (J - 1) / 2; 0 without the LCA task
  int64_t correct_pairs = 0;   // pairs whose predicted LCA (argmax) is right
  bool rebuilt = false;        // the predicted LCA matrix gives back exactly the true parent array
  std::string rebuild_failure; // why not (rebuild_tree's message, or "a different tree"); empty when rebuilt
  bool decoded = false;        // the tree decoded from the predicted LCA probabilities is the true parent array
  int decoded_wrong_parents = 0;  // joints whose parent in that decoded tree is wrong
  double offset_error = 0.0;   // mean |predicted - true| rest offset over non-root joints, graph units
  double offset_percent = 0.0; // the same in per cent of the skeleton's diameter
  bool has_lca = false;        // the model has the LCA task
  bool has_offset = false;     // the model has the offset task

  double lca_accuracy() const { return pairs > 0 ? static_cast<double>(correct_pairs) / pairs : 0.0; }
};

// Scores every skeleton as is (no augmentation), in input order. Names come
// from `vectors` when the model reads names (name_dim > 0) and `vectors` is
// given; otherwise the skeletons go in without names. `max_batch_floats`
// bounds B * J^3 of the all-pair logits per batch.
std::vector<SkeletonScore> score_skeletons(OwoPretrainerImpl& model, const std::vector<PretrainSkeleton>& skeletons,
                                           const text::WordVectors* vectors, const c10::Device& device,
                                           int64_t max_batch_floats = int64_t{1} << 24);

struct ScoreSummary {
  int skeletons = 0;
  int min_joints = 0, max_joints = 0;
  double lca_accuracy = 0.0;          // correct pairs / pairs, pooled over all skeletons
  double mean_lca_accuracy = 0.0;     // mean of the per-skeleton accuracies
  double offset_error = 0.0;          // mean of the per-skeleton offset errors, graph units
  double offset_percent = 0.0;        // mean of the per-skeleton errors in per cent of the diameter
  int rebuilt = 0;                    // skeletons rebuilt exactly from the predicted LCA matrix
  double rebuild_rate = 0.0;          // rebuilt / skeletons
  int decoded = 0;                    // skeletons rebuilt from the predicted LCA probabilities
  double decode_rate = 0.0;           // decoded / skeletons
};

ScoreSummary summarize(const std::vector<SkeletonScore>& scores);

}  // namespace nec::owo

// Scores of a pretrained OwO model on whole skeletons: all-pair LCA, offsets, tree rebuild.
#include "nec/owo/evaluation.h"

#include "nec/owo/graph.h"
#include "nec/owo/joint_names.h"
#include "nec/owo/tree_rebuild.h"

#include <torch/torch.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace nec::owo {

std::vector<SkeletonScore> score_skeletons(OwoPretrainerImpl& model, const std::vector<PretrainSkeleton>& skeletons,
                                           const text::WordVectors* vectors, const c10::Device& device,
                                           int64_t max_batch_floats) {
  const OwoConfig& config = model.encoder->config();
  const bool use_names = config.name_dim > 0 && vectors != nullptr;
  if (use_names && vectors->dim() != config.name_dim) {
    throw std::invalid_argument("score_skeletons: the model reads " + std::to_string(config.name_dim) +
                                "-d names, the word vectors are " + std::to_string(vectors->dim()) + "-d");
  }
  const bool has_lca = model.config().lca_loss;
  const bool has_offset = model.config().offset_loss;
  torch::NoGradGuard no_grad;

  // Batches of similar size, biggest first.
  std::vector<size_t> order(skeletons.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return skeletons[a].skeleton.joint_count() > skeletons[b].skeleton.joint_count();
  });
  std::vector<SkeletonScore> scores(skeletons.size());
  size_t next = 0;
  while (next < order.size()) {
    const int64_t largest = skeletons[order[next]].skeleton.joint_count();
    const int64_t per_skeleton = std::max<int64_t>(1, largest * largest * largest);
    const size_t batch_size = static_cast<size_t>(std::max<int64_t>(1, max_batch_floats / per_skeleton));
    const size_t end = std::min(order.size(), next + batch_size);

    std::vector<SkeletonGraph> graphs;
    for (size_t k = next; k < end; ++k) {
      const PretrainSkeleton& s = skeletons[order[k]];
      const at::Tensor names = use_names ? name_embeddings(*vectors, s.canonical_names) : at::Tensor();
      graphs.push_back(make_skeleton_graph(s.skeleton, names, config.graph));
    }
    const GraphBatch batch = collate(graphs, config.name_dim).to(device);
    at::Tensor lca_logits;  // (B, J, J, J)
    std::vector<at::Tensor> predicted_lca;
    if (has_lca) {
      lca_logits = model.all_pair_lca_logits(batch).to(torch::kCPU);
      predicted_lca = lca_matrices_from_logits(lca_logits, batch.joint_counts);
    }
    at::Tensor offsets;
    if (has_offset) offsets = model.predicted_offsets(batch).to(torch::kCPU);  // (B, J, 3)

    for (size_t k = next; k < end; ++k) {
      const size_t b = k - next;
      const PretrainSkeleton& s = skeletons[order[k]];
      const SkeletonGraph& graph = graphs[b];
      const int64_t joints = graph.joint_count;
      SkeletonScore& score = scores[order[k]];
      score.name = s.name;
      score.group = s.group;
      score.joints = static_cast<int>(joints);
      score.has_lca = has_lca;
      score.has_offset = has_offset;
      if (has_lca) {
        // LCA(i, i) = i by definition: only pairs i != j are the model's answers (C.4 asks no others).
        const at::Tensor predicted = predicted_lca[b].clone();  // (J, J)
        predicted.diagonal().copy_(torch::arange(joints, torch::kInt64));
        const at::Tensor upper = torch::ones({joints, joints}, torch::kBool).triu(1);
        score.pairs = joints * (joints - 1) / 2;
        score.correct_pairs = (predicted == graph.lca).logical_and(upper).sum().item<int64_t>();
        const RebuiltTree tree = rebuild_tree(predicted);
        if (!tree.ok()) {
          score.rebuild_failure = tree.failure;
        } else if (tree.parents != s.skeleton.parents) {
          score.rebuild_failure = "a valid tree, but a different one";
        } else {
          score.rebuilt = true;
        }
        const RebuiltTree decoded =
            decode_tree(lca_logits[b].slice(0, 0, joints).slice(1, 0, joints).slice(2, 0, joints));
        for (int64_t i = 0; i < joints; ++i) score.decoded_wrong_parents += decoded.parents[i] != s.skeleton.parents[i];
        score.decoded = score.decoded_wrong_parents == 0;
      }
      if (has_offset && joints > 1) {
        const at::Tensor error =
            (offsets[b].narrow(0, 1, joints - 1) - graph.rest_offsets.narrow(0, 1, joints - 1)).norm(2, -1);  // (J-1)
        score.offset_error = error.mean().item<double>();
        const double diameter = config.graph.normalize_scale ? 1.0 : s.skeleton.diameter();
        score.offset_percent = diameter > 0.0 ? 100.0 * score.offset_error / diameter : 0.0;
      }
    }
    next = end;
  }
  return scores;
}

ScoreSummary summarize(const std::vector<SkeletonScore>& scores) {
  ScoreSummary summary;
  summary.skeletons = static_cast<int>(scores.size());
  if (scores.empty()) return summary;
  int64_t pairs = 0, correct = 0;
  summary.min_joints = scores.front().joints;
  summary.max_joints = scores.front().joints;
  for (const SkeletonScore& s : scores) {
    summary.min_joints = std::min(summary.min_joints, s.joints);
    summary.max_joints = std::max(summary.max_joints, s.joints);
    pairs += s.pairs;
    correct += s.correct_pairs;
    summary.mean_lca_accuracy += s.lca_accuracy() / scores.size();
    summary.offset_error += s.offset_error / scores.size();
    summary.offset_percent += s.offset_percent / scores.size();
    summary.rebuilt += s.rebuilt ? 1 : 0;
    summary.decoded += s.decoded ? 1 : 0;
  }
  summary.lca_accuracy = pairs > 0 ? static_cast<double>(correct) / pairs : 0.0;
  summary.rebuild_rate = static_cast<double>(summary.rebuilt) / scores.size();
  summary.decode_rate = static_cast<double>(summary.decoded) / scores.size();
  return summary;
}

}  // namespace nec::owo

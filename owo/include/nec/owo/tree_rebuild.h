// Skeleton tree reconstruction from lowest common ancestors (NECromancer
// appendix C.4): when LCA(i, j) is right for every pair, the tree is unique,
// and this rebuilds its parent array. A matrix that is not the LCA matrix of
// any tree (a predicted one with mistakes) is reported, never guessed around.
//
//   at::Tensor logits = pretrainer->all_pair_lca_logits(batch);                    // (B, J, J, J)
//   std::vector<at::Tensor> lca = lca_matrices_from_logits(logits, batch.joint_counts);
//   RebuiltTree tree = rebuild_tree(lca[0]);                                        // or batch.lca[0]
//   if (tree.ok()) use(tree.parents); else report(tree.failure);
#pragma once

#include <ATen/core/Tensor.h>

#include <string>
#include <vector>

namespace nec::owo {

struct RebuiltTree {
  std::vector<int> parents;  // (J) parent of each joint, -1 for the root; empty on failure
  std::string failure;       // why the matrix is no tree's LCA matrix; empty on success

  bool ok() const { return failure.empty(); }
};

// `lca` (J, J) integer, any device: lca[i][j] = lowest common ancestor of
// joints i and j. Succeeds exactly when `lca` is the LCA matrix of a tree on
// joints 0..J-1 (the root need not be joint 0, nor parents come before
// children); then recomputing the LCAs from `parents` gives `lca` back.
RebuiltTree rebuild_tree(const at::Tensor& lca);

// Per-skeleton predicted LCA matrices from all-pair pointer logits
// (B, J, J, J) and joint counts (B): the argmax over candidates, cut to each
// skeleton's own joints. Returns B CPU int64 tensors of shape (J_b, J_b).
std::vector<at::Tensor> lca_matrices_from_logits(const at::Tensor& logits, const at::Tensor& joint_counts);

}  // namespace nec::owo

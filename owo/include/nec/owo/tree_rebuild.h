// Skeleton tree reconstruction from lowest common ancestors (NECromancer
// appendix C.4), two ways:
// - rebuild_tree (strict): when LCA(i, j) is right for every pair, the tree is
//   unique, and this rebuilds its parent array. A matrix that is not the LCA
//   matrix of any tree (a predicted one with mistakes) is reported, never
//   guessed around. One wrong pair of a 50-joint skeleton's 1,225 fails it.
// - decode_tree (from probabilities): the tree that best agrees with the
//   predicted LCA distributions of all pairs; always a tree, right when the
//   probabilities lean the right way on enough pairs (see decode_tree).
//
//   at::Tensor logits = pretrainer->all_pair_lca_logits(batch);                    // (B, J, J, J)
//   std::vector<at::Tensor> lca = lca_matrices_from_logits(logits, batch.joint_counts);
//   RebuiltTree tree = rebuild_tree(lca[0]);                                        // or batch.lca[0]
//   if (tree.ok()) use(tree.parents); else report(tree.failure);
//   int64_t n = batch.joint_counts[0].item<int64_t>();
//   RebuiltTree decoded = decode_tree(logits[0].slice(0, 0, n).slice(1, 0, n).slice(2, 0, n));
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

// `lca_logits` (J, J, J) float, any device: [i, j, k] scores joint k as
// LCA(i, j) (softmax over k, both orders averaged; the diagonal i = j is not
// read). In a tree, a is the parent of i exactly when LCA(a, i) = a and every
// other joint x has LCA(i, x) = LCA(a, x), except the joints x under i, where
// LCA(i, x) = i and LCA(a, x) = a. So a -> i is scored by how well the
// predicted distributions agree with that:
//   w(a -> i) = log p(LCA(i, a) = a) + sum over x != a, i of log(
//               sum over k != i of p(LCA(i, x) = k) p(LCA(a, x) = k) + p(LCA(i, x) = i) p(LCA(a, x) = a)),
// the root r by sum over x != r of log p(LCA(r, x) = r), and the tree starts
// as the maximum spanning arborescence (Chu-Liu/Edmonds) from the best root.
// Then subtrees move to new parents while that raises the tree's
// log-likelihood, the sum over ordered pairs x != y of log p(LCA(x, y) = the
// tree's LCA(x, y)); the root stays. O(J^4) for the edge scores (a batched
// matrix product), O(J^3) per sweep of moves. Fails only for malformed input
// (not (J, J, J), J = 0, not floating point). Reads nothing but `lca_logits`.
RebuiltTree decode_tree(const at::Tensor& lca_logits);

// Per-skeleton predicted LCA matrices from all-pair pointer logits
// (B, J, J, J) and joint counts (B): the argmax over candidates, cut to each
// skeleton's own joints. Returns B CPU int64 tensors of shape (J_b, J_b).
std::vector<at::Tensor> lca_matrices_from_logits(const at::Tensor& logits, const at::Tensor& joint_counts);

}  // namespace nec::owo

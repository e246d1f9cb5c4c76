// Skeleton tree reconstruction from lowest common ancestors (NECromancer
// appendix C.4), two ways:
// - rebuild_tree (strict): when LCA(i, j) is right for every pair, the tree is
//   unique, and this rebuilds its parent array. A matrix that is not the LCA
//   matrix of any tree (a predicted one with mistakes) is reported, never
//   guessed around. One wrong pair of a 50-joint skeleton's 1,225 fails it.
// - decode_tree (from probabilities): a tree that agrees best with the
//   predicted LCA distributions of all pairs (votes, then a likelihood climb);
//   always a tree, right when the probabilities lean the right way on enough
//   pairs. Scored the same way: right only if it is the true parent array.
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
// LCA(i, j) (softmax over k; the diagonal i = j is not read). The tree that
// best explains them, in two stages:
// 1. Votes. Each pair (i, x) names one joint, the most probable over both
//    orders. In a tree, a is the parent of i exactly when LCA(i, a) = a and
//    every other joint x has LCA(i, x) = LCA(a, x), except the joints x under
//    i, where LCA(i, x) = i and LCA(a, x) = a; the edge a -> i gets one vote
//    per condition the named joints meet, a root r one per x with
//    LCA(r, x) = r. The start is the maximum spanning arborescence
//    (Chu-Liu/Edmonds) of the votes, from each of the 3 best roots.
// 2. Likelihood climb. Moves (a subtree to a new parent, or a joint swapped
//    with its parent) while they raise the log-likelihood, the sum over
//    ordered pairs x != y of log p(LCA(x, y) = the tree's LCA(x, y)), at most
//    J moves. The root with the best final likelihood wins.
// Always a tree for J >= 1, and right when the probabilities lean the right
// way on enough pairs; not guaranteed to be the most likely tree (a local
// search). O(J^3) for the votes, up to O(J^3 depth) per move. Fails only for
// malformed input (not (J, J, J), J = 0, not floating point). Reads nothing
// but `lca_logits`.
RebuiltTree decode_tree(const at::Tensor& lca_logits);

// Per-skeleton predicted LCA matrices from all-pair pointer logits
// (B, J, J, J) and joint counts (B): the argmax over candidates, cut to each
// skeleton's own joints. Returns B CPU int64 tensors of shape (J_b, J_b).
std::vector<at::Tensor> lca_matrices_from_logits(const at::Tensor& logits, const at::Tensor& joint_counts);

}  // namespace nec::owo

// Parent array from an LCA matrix (appendix C.4), with a full consistency check.
//
// Joint a is an ancestor-or-self of i exactly when LCA(a, i) = a. The root is
// the one joint that is an ancestor of every joint; the parent of any other
// joint is its deepest proper ancestor, the one with the most ancestors itself.
// The candidate tree is then checked by recomputing every LCA, so any success
// reproduces the input exactly, and by uniqueness is the true tree.
#include "nec/owo/tree_rebuild.h"

#include <torch/torch.h>

#include <cstdint>
#include <string>

namespace nec::owo {
namespace {

RebuiltTree failed(std::string why) {
  RebuiltTree tree;
  tree.failure = std::move(why);
  return tree;
}

std::string pair_name(int64_t i, int64_t j) {
  return "LCA(" + std::to_string(i) + ", " + std::to_string(j) + ")";
}

}  // namespace

RebuiltTree rebuild_tree(const at::Tensor& lca) {
  if (!lca.defined() || lca.dim() != 2 || lca.size(0) != lca.size(1)) {
    return failed("the LCA matrix must be square (J, J)");
  }
  if (at::isFloatingType(lca.scalar_type()) || lca.scalar_type() == at::kBool) {
    return failed("the LCA matrix must hold integer joint indices");
  }
  const int64_t j = lca.size(0);
  if (j == 0) return failed("the LCA matrix is empty");
  const at::Tensor cpu = lca.to(torch::kCPU, torch::kInt64).contiguous();
  const int64_t* m = cpu.data_ptr<int64_t>();
  auto at_pair = [&](int64_t a, int64_t b) { return m[a * j + b]; };

  for (int64_t a = 0; a < j; ++a) {
    if (at_pair(a, a) != a) return failed(pair_name(a, a) + " is " + std::to_string(at_pair(a, a)) + ", not " + std::to_string(a));
    for (int64_t b = 0; b < j; ++b) {
      const int64_t value = at_pair(a, b);
      if (value < 0 || value >= j) {
        return failed(pair_name(a, b) + " = " + std::to_string(value) + " is not a joint index in [0, " + std::to_string(j) + ")");
      }
      if (value != at_pair(b, a)) {
        return failed(pair_name(a, b) + " = " + std::to_string(value) + " but " + pair_name(b, a) + " = " + std::to_string(at_pair(b, a)));
      }
    }
  }

  // ancestor_count[i]: joints a != i with LCA(a, i) = a.
  std::vector<int64_t> ancestor_count(j, 0);
  for (int64_t i = 0; i < j; ++i) {
    for (int64_t a = 0; a < j; ++a) {
      if (a != i && at_pair(a, i) == a) ++ancestor_count[i];
    }
  }

  std::vector<int> parents(j, -1);
  int64_t root = -1;
  for (int64_t i = 0; i < j; ++i) {
    int64_t parent = -1;
    for (int64_t a = 0; a < j; ++a) {
      if (a == i || at_pair(a, i) != a) continue;
      if (ancestor_count[a] >= ancestor_count[i]) {
        return failed("joint " + std::to_string(a) + " is an ancestor of joint " + std::to_string(i) +
                      " but has as many ancestors itself (ancestors that form no chain, or a cycle)");
      }
      if (parent < 0 || ancestor_count[a] > ancestor_count[parent]) parent = a;
    }
    if (parent < 0) {
      if (root >= 0) return failed("joints " + std::to_string(root) + " and " + std::to_string(i) + " both have no ancestor (two roots)");
      root = i;
    }
    parents[i] = static_cast<int>(parent);
  }
  if (root < 0) return failed("no joint is an ancestor of every other (no root)");

  // Ancestor counts strictly decrease towards the parent, so every chain ends at the root.
  std::vector<int64_t> depth(j, -1);
  for (int64_t i = 0; i < j; ++i) {
    int64_t steps = 0;
    for (int64_t k = i; parents[k] >= 0; k = parents[k]) ++steps;
    depth[i] = steps;
  }
  for (int64_t a = 0; a < j; ++a) {
    for (int64_t b = a + 1; b < j; ++b) {
      int64_t x = a, y = b;
      while (depth[x] > depth[y]) x = parents[x];
      while (depth[y] > depth[x]) y = parents[y];
      while (x != y) {
        x = parents[x];
        y = parents[y];
      }
      if (x != at_pair(a, b)) {
        return failed(pair_name(a, b) + " = " + std::to_string(at_pair(a, b)) + " contradicts the other pairs, which give " +
                      std::to_string(x));
      }
    }
  }
  RebuiltTree tree;
  tree.parents = std::move(parents);
  return tree;
}

std::vector<at::Tensor> lca_matrices_from_logits(const at::Tensor& logits, const at::Tensor& joint_counts) {
  TORCH_CHECK(logits.dim() == 4 && logits.size(1) == logits.size(2) && logits.size(2) == logits.size(3),
              "lca_matrices_from_logits: logits must be (B, J, J, J), got ", logits.sizes());
  TORCH_CHECK(joint_counts.dim() == 1 && joint_counts.size(0) == logits.size(0),
              "lca_matrices_from_logits: joint_counts must be (B)");
  const at::Tensor argmax = logits.argmax(-1).to(torch::kCPU, torch::kInt64);  // (B, J, J)
  const at::Tensor counts = joint_counts.to(torch::kCPU, torch::kInt64);
  std::vector<at::Tensor> matrices;
  for (int64_t b = 0; b < logits.size(0); ++b) {
    const int64_t n = counts[b].item<int64_t>();
    matrices.push_back(argmax[b].slice(0, 0, n).slice(1, 0, n).contiguous());
  }
  return matrices;
}

}  // namespace nec::owo

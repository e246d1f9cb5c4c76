// Parent arrays from LCAs (appendix C.4): exactly from an LCA matrix, with a
// full consistency check, or as the best-agreeing tree from LCA probabilities.
//
// Joint a is an ancestor-or-self of i exactly when LCA(a, i) = a. The root is
// the one joint that is an ancestor of every joint; the parent of any other
// joint is its deepest proper ancestor, the one with the most ancestors itself.
// The candidate tree is then checked by recomputing every LCA, so any success
// reproduces the input exactly, and by uniqueness is the true tree.
#include "nec/owo/tree_rebuild.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
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

constexpr double kNoEdge = -std::numeric_limits<double>::infinity();
constexpr double kMinGain = 1e-9;  // likelihood climb: smaller gains are rounding noise, and could cycle

// A cycle of the parent pointers `parents` (-1: none), as its nodes; empty when there is none.
std::vector<int> find_cycle(const std::vector<int>& parents) {
  enum State { kUnseen, kOnPath, kDone };
  std::vector<State> state(parents.size(), kUnseen);
  for (size_t start = 0; start < parents.size(); ++start) {
    int v = static_cast<int>(start);
    while (v >= 0 && state[v] == kUnseen) {
      state[v] = kOnPath;
      v = parents[v];
    }
    if (v >= 0 && state[v] == kOnPath) {
      std::vector<int> cycle;
      int c = v;
      do {
        cycle.push_back(c);
        c = parents[c];
      } while (c != v);
      return cycle;
    }
    for (v = static_cast<int>(start); v >= 0 && state[v] == kOnPath; v = parents[v]) state[v] = kDone;
  }
  return {};
}

// Maximum spanning arborescence rooted at `root` of the dense digraph on n
// nodes with edge a -> i scored score[a * n + i] (kNoEdge: absent; every node
// but the root needs an incoming edge). Chu-Liu/Edmonds: take each node's best
// incoming edge; a cycle among them is contracted into one node, whose incoming
// edges are scored by what they gain over the cycle edge they replace, and the
// smaller problem's answer is expanded back. O(n^3). Returns parents (root: -1).
std::vector<int> max_arborescence(const std::vector<double>& score, int n, int root) {
  std::vector<int> best(n, -1);
  for (int i = 0; i < n; ++i) {
    if (i == root) continue;
    for (int a = 0; a < n; ++a) {
      const double s = score[a * n + i];
      if (a != i && s > kNoEdge && (best[i] < 0 || s > score[best[i] * n + i])) best[i] = a;
    }
  }
  const std::vector<int> cycle = find_cycle(best);
  if (cycle.empty()) return best;

  std::vector<bool> in_cycle(n, false);
  for (int c : cycle) in_cycle[c] = true;
  std::vector<int> new_index(n), old_index;  // old_index: reduced node -> node, outside the cycle
  for (int v = 0; v < n; ++v) {
    if (in_cycle[v]) continue;
    new_index[v] = static_cast<int>(old_index.size());
    old_index.push_back(v);
  }
  const int contracted = static_cast<int>(old_index.size()), m = contracted + 1;
  for (int c : cycle) new_index[c] = contracted;
  std::vector<double> reduced(static_cast<size_t>(m) * m, kNoEdge);
  std::vector<int> enters_at(m, -1);   // reduced u -> the cycle node its best edge into the cycle reaches
  std::vector<int> leaves_from(m, -1);  // reduced v -> the cycle node whose edge to v is best
  for (int a = 0; a < n; ++a) {
    for (int i = 0; i < n; ++i) {
      const double s = score[a * n + i];
      if (a == i || s == kNoEdge || (in_cycle[a] && in_cycle[i])) continue;
      const int from = new_index[a], to = new_index[i];
      double& slot = reduced[static_cast<size_t>(from) * m + to];
      if (in_cycle[i]) {
        const double gain = s - score[best[i] * n + i];
        if (gain > slot) {
          slot = gain;
          enters_at[from] = i;
        }
      } else if (in_cycle[a]) {
        if (s > slot) {
          slot = s;
          leaves_from[to] = a;
        }
      } else {
        slot = s;
      }
    }
  }
  const std::vector<int> reduced_parents = max_arborescence(reduced, m, new_index[root]);

  std::vector<int> parents(n, -1);
  for (int v = 0; v < n; ++v) {
    if (v == root) continue;
    if (in_cycle[v]) {
      parents[v] = best[v];
      continue;
    }
    const int p = reduced_parents[new_index[v]];
    parents[v] = p == contracted ? leaves_from[new_index[v]] : old_index[p];
  }
  const int entry = reduced_parents[contracted];  // the one edge into the cycle breaks it there
  parents[enters_at[entry]] = old_index[entry];
  return parents;
}

// LCA matrix [x * n + y] of the tree `parents`, by walking up from the deeper joint.
std::vector<int> lca_matrix(const std::vector<int>& parents) {
  const int n = static_cast<int>(parents.size());
  std::vector<int> depth(n, 0);
  for (int v = 0; v < n; ++v) {
    for (int k = parents[v]; k >= 0; k = parents[k]) ++depth[v];
  }
  std::vector<int> lca(static_cast<size_t>(n) * n);
  for (int x = 0; x < n; ++x) {
    for (int y = x; y < n; ++y) {
      int a = x, b = y;
      while (depth[a] > depth[b]) a = parents[a];
      while (depth[b] > depth[a]) b = parents[b];
      while (a != b) {
        a = parents[a];
        b = parents[b];
      }
      lca[x * n + y] = lca[y * n + x] = a;
    }
  }
  return lca;
}

// Log-likelihood of the tree with LCA matrix `lca`: the sum over ordered pairs
// x != y of lp[(x * n + y) * n + lca[x * n + y]].
double tree_log_likelihood(const std::vector<int>& lca, const double* lp, int n) {
  double sum = 0.0;
  for (int x = 0; x < n; ++x) {
    for (int y = 0; y < n; ++y) {
      if (x != y) sum += lp[(static_cast<int64_t>(x) * n + y) * n + lca[x * n + y]];
    }
  }
  return sum;
}

// `parents` with joint v and its parent w trading places: v takes w's parent,
// w hangs under v, and each keeps the other's remaining children.
std::vector<int> swapped_with_parent(std::vector<int> parents, int v) {
  const int w = parents[v];
  for (int& parent : parents) {
    if (parent == v) {
      parent = w;
    } else if (parent == w) {
      parent = v;
    }
  }
  parents[v] = parents[w];  // the loop left w's own entry, its parent, alone
  parents[w] = v;
  return parents;
}

// The subtree move that raises the log-likelihood most: hang the subtree S of
// a joint v under another joint u outside it. Only pairs (x in S, y outside)
// change their LCA, from LCA(v, y) to LCA(u, y), so only they are summed.
// `lca` is the matrix of `parents`. Returns the new parents; empty when no move gains.
std::vector<int> best_subtree_move(const std::vector<int>& parents, const std::vector<int>& lca, const double* lp) {
  const int n = static_cast<int>(parents.size());
  auto pair_log_p = [&](int x, int y, int k) {
    return lp[(static_cast<int64_t>(x) * n + y) * n + k] + lp[(static_cast<int64_t>(y) * n + x) * n + k];
  };
  double best_gain = kMinGain;
  int best_joint = -1, best_parent = -1;
  for (int v = 0; v < n; ++v) {
    if (parents[v] < 0) continue;
    std::vector<int> inside, outside;
    for (int x = 0; x < n; ++x) (lca[x * n + v] == v ? inside : outside).push_back(x);
    for (int u : outside) {
      if (u == parents[v]) continue;
      double gain = 0.0;
      for (int y : outside) {
        const int before = lca[v * n + y], after = lca[u * n + y];
        if (before == after) continue;
        for (int x : inside) gain += pair_log_p(x, y, after) - pair_log_p(x, y, before);
      }
      if (gain > best_gain) {
        best_gain = gain;
        best_joint = v;
        best_parent = u;
      }
    }
  }
  if (best_joint < 0) return {};
  std::vector<int> moved = parents;
  moved[best_joint] = best_parent;
  return moved;
}

// The swap of a joint with its parent that raises the log-likelihood (`likelihood`
// now) most; empty when none does. Each candidate is scored in full, O(J^2 depth).
std::vector<int> best_parent_swap(const std::vector<int>& parents, double likelihood, const double* lp) {
  const int n = static_cast<int>(parents.size());
  double best_gain = kMinGain;
  std::vector<int> best;
  for (int v = 0; v < n; ++v) {
    if (parents[v] < 0) continue;
    std::vector<int> swapped = swapped_with_parent(parents, v);
    const double gain = tree_log_likelihood(lca_matrix(swapped), lp, n) - likelihood;
    if (gain > best_gain) {
      best_gain = gain;
      best = std::move(swapped);
    }
  }
  return best;
}

// Hill climbing on the tree's log-likelihood. The arborescence's edge votes
// count each pair once, right or wrong; this weighs every pair a move changes
// by its probabilities. Each step makes the best subtree move (the best, not
// the first found: that can hang a joint under its own descendants, out of
// reach of later moves), or when none gains, the best swap of a joint with its
// parent (two neighbours on a chain in the wrong order, which no subtree move
// undoes), until neither gains, or after J moves: predictions that need more
// are far from any tree, and a step costs up to O(J^3) (a 140-joint skeleton
// with poor predictions took ~15 s without the bound). lp: log-probabilities
// [(x * n + y) * n + k]. Returns the final log-likelihood.
double climb_likelihood(std::vector<int>& parents, const double* lp) {
  const int n = static_cast<int>(parents.size());
  for (int moves = 0;; ++moves) {
    const std::vector<int> lca = lca_matrix(parents);
    const double likelihood = tree_log_likelihood(lca, lp, n);
    if (moves == n) return likelihood;
    std::vector<int> next = best_subtree_move(parents, lca, lp);
    if (next.empty()) next = best_parent_swap(parents, likelihood, lp);
    if (next.empty()) return likelihood;
    parents = std::move(next);
  }
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

RebuiltTree decode_tree(const at::Tensor& lca_logits) {
  if (!lca_logits.defined() || lca_logits.dim() != 3 || lca_logits.size(0) != lca_logits.size(1) ||
      lca_logits.size(1) != lca_logits.size(2)) {
    return failed("the LCA logits must be (J, J, J)");
  }
  if (!at::isFloatingType(lca_logits.scalar_type())) return failed("the LCA logits must be floating point");
  const int n = static_cast<int>(lca_logits.size(0));
  if (n == 0) return failed("the LCA logits are empty");
  const at::Tensor log_probs = torch::log_softmax(lca_logits.to(torch::kCPU, torch::kFloat64), -1).contiguous();
  const double* lp = log_probs.data_ptr<double>();

  // named[i * n + x]: the joint the two orders of pair (i, x) together find most probable as its LCA.
  at::Tensor probs = log_probs.exp();
  probs = probs + probs.transpose(0, 1);
  const at::Tensor named_tensor = probs.argmax(-1).contiguous();  // (J, J) int64
  const int64_t* named = named_tensor.data_ptr<int64_t>();
  auto lca_named = [&](int i, int x) { return i == x ? i : static_cast<int>(named[i * n + x]); };

  // Votes, not probabilities: a sum of log-probabilities over all x would add
  // up the noise of every pair, most of which says nothing about a -> i.
  std::vector<double> score(static_cast<size_t>(n) * n, kNoEdge);  // [a * n + i] = w(a -> i)
  for (int i = 0; i < n; ++i) {
    for (int a = 0; a < n; ++a) {
      if (a == i) continue;
      int votes = lca_named(i, a) == a;
      for (int x = 0; x < n; ++x) {
        if (x == a || x == i) continue;
        // x under i: LCA(i, x) = i and LCA(a, x) = a; elsewhere both pairs name the same joint.
        const int from_i = lca_named(i, x);
        votes += from_i == i ? lca_named(a, x) == a : lca_named(a, x) == from_i;
      }
      score[a * n + i] = votes;
    }
  }

  // A few roots, best first: a wrong root cannot be repaired by moving subtrees.
  std::vector<std::pair<int, int>> roots;  // (votes: joints x with LCA(r, x) = r, joint r)
  for (int r = 0; r < n; ++r) {
    int votes = 0;
    for (int x = 0; x < n; ++x) votes += x != r && lca_named(r, x) == r;
    roots.emplace_back(votes, r);
  }
  constexpr int kRootCandidates = 3;
  const int candidates = std::min(n, kRootCandidates);
  std::partial_sort(roots.begin(), roots.begin() + candidates, roots.end(), std::greater<>());
  RebuiltTree best;
  double best_likelihood = kNoEdge;
  for (int c = 0; c < candidates; ++c) {
    const int root = roots[c].second;
    std::vector<double> rooted = score;
    for (int a = 0; a < n; ++a) rooted[a * n + root] = kNoEdge;
    std::vector<int> parents = max_arborescence(rooted, n, root);
    const double likelihood = climb_likelihood(parents, lp);
    if (likelihood > best_likelihood) {
      best_likelihood = likelihood;
      best.parents = std::move(parents);
    }
  }
  return best;
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

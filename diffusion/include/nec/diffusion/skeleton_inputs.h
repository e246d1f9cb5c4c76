// What the denoiser knows of a skeleton, per joint: the frozen OwO joint
// embeddings h_j (the design card's choice), and the paper's fixed encodings
// it compares against: the tree position (TreePE, Shiv & Quirk 2019) and the
// rest offset (RestPE, a NeRF-style sinusoidal encoding).
//
//   const at::Tensor tree = tree_positions(parents);   // (B, J) int64 -> (B, J, kTreeFeatures)
//   const at::Tensor rest = rest_positions(offsets);   // (B, J, 3)   -> (B, J, kRestFeatures)
//
// TreePE: a joint's path from the root as one one-hot per level, the child
// index at that level (children numbered in joint order, index
// kTreeBranches − 1 for the later ones), levels below kTreeDepth dropped; the
// root is all zeros. RestPE: [p, sin(2^k π p), cos(2^k π p)] for k < kRestFrequencies
// of the offset p in normalized units (skeleton diameter 1).
#pragma once

#include "nec/motion/skeleton.h"

#include <ATen/core/Tensor.h>
#include <c10/core/Device.h>

#include <cstdint>
#include <vector>

namespace nec::diffusion {

constexpr int64_t kTreeBranches = 8;
constexpr int64_t kTreeDepth = 24;
constexpr int64_t kTreeFeatures = kTreeBranches * kTreeDepth;
constexpr int64_t kRestFrequencies = 6;
constexpr int64_t kRestFeatures = 3 * (1 + 2 * kRestFrequencies);

// parents (B, J) int64, −1 for roots and padding (a padded joint is a root: zeros) -> (B, J, kTreeFeatures) float32.
at::Tensor tree_positions(const at::Tensor& parents);
// offsets (B, J, 3) float32 -> (B, J, kRestFeatures) float32.
at::Tensor rest_positions(const at::Tensor& offsets);

// The skeletons of a batch as the denoiser reads them.
struct SkeletonInputs {
  at::Tensor joint_embeddings;  // (B, J, E) OwO h_j, zero at padding
  at::Tensor tree;              // (B, J, kTreeFeatures)
  at::Tensor rest;              // (B, J, kRestFeatures)
  at::Tensor joint_mask;        // (B, J) bool

  SkeletonInputs to(const c10::Device& device) const;
  // Rows `rows` (int64 indices) of every part, e.g. one skeleton repeated over samples.
  SkeletonInputs select(const at::Tensor& rows) const;
};

// From a batch's parents (B, J) int64, offsets (B, J, 3), joint mask (B, J) and OwO embeddings (B, J, E).
SkeletonInputs make_skeleton_inputs(const at::Tensor& parents, const at::Tensor& offsets, const at::Tensor& joint_mask,
                                    const at::Tensor& joint_embeddings);
// One normalized skeleton (B = 1) with its OwO embeddings (J, E).
SkeletonInputs make_skeleton_inputs(const Skeleton& skeleton, const at::Tensor& joint_embeddings);

}  // namespace nec::diffusion

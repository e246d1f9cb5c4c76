// TreePE and RestPE inputs, and a batch's skeletons as the denoiser reads them.
#include "nec/diffusion/skeleton_inputs.h"

#include <torch/torch.h>

#include <cmath>

namespace nec::diffusion {

at::Tensor tree_positions(const at::Tensor& parents) {
  const at::Tensor cpu = parents.to(torch::kCPU, torch::kInt64).contiguous();
  const int64_t b = cpu.size(0), j = cpu.size(1);
  at::Tensor out = torch::zeros({b, j, kTreeFeatures});
  auto p = cpu.accessor<int64_t, 2>();
  auto o = out.accessor<float, 3>();
  for (int64_t item = 0; item < b; ++item) {
    // The child index of each joint among its parent's children, in joint order.
    std::vector<int64_t> child_index(static_cast<size_t>(j), 0), children(static_cast<size_t>(j), 0);
    for (int64_t joint = 0; joint < j; ++joint) {
      const int64_t parent = p[item][joint];
      if (parent >= 0) child_index[static_cast<size_t>(joint)] = children[static_cast<size_t>(parent)]++;
    }
    for (int64_t joint = 0; joint < j; ++joint) {
      std::vector<int64_t> path;  // child indices from the joint up to the root
      for (int64_t at = joint; p[item][at] >= 0; at = p[item][at]) path.push_back(child_index[static_cast<size_t>(at)]);
      const int64_t depth = static_cast<int64_t>(path.size());
      for (int64_t level = 0; level < std::min(depth, kTreeDepth); ++level) {
        const int64_t branch = std::min(path[static_cast<size_t>(depth - 1 - level)], kTreeBranches - 1);
        o[item][joint][level * kTreeBranches + branch] = 1.0f;
      }
    }
  }
  return out.to(parents.device());
}

at::Tensor rest_positions(const at::Tensor& offsets) {
  std::vector<at::Tensor> parts{offsets};
  for (int64_t k = 0; k < kRestFrequencies; ++k) {
    const at::Tensor scaled = offsets * (std::pow(2.0, static_cast<double>(k)) * M_PI);
    parts.push_back(torch::sin(scaled));
    parts.push_back(torch::cos(scaled));
  }
  return torch::cat(parts, -1);
}

SkeletonInputs SkeletonInputs::to(const c10::Device& device) const {
  return {joint_embeddings.to(device), tree.to(device), rest.to(device), joint_mask.to(device)};
}

SkeletonInputs SkeletonInputs::select(const at::Tensor& rows) const {
  const at::Tensor r = rows.to(joint_mask.device());
  return {joint_embeddings.index_select(0, r), tree.index_select(0, r), rest.index_select(0, r),
          joint_mask.index_select(0, r)};
}

SkeletonInputs make_skeleton_inputs(const at::Tensor& parents, const at::Tensor& offsets, const at::Tensor& joint_mask,
                                    const at::Tensor& joint_embeddings) {
  const at::Tensor real = joint_mask.unsqueeze(-1).to(torch::kFloat32);
  return {joint_embeddings, tree_positions(parents), rest_positions(offsets) * real, joint_mask};
}

SkeletonInputs make_skeleton_inputs(const Skeleton& skeleton, const at::Tensor& joint_embeddings) {
  const int64_t j = skeleton.joint_count();
  std::vector<int64_t> parents(skeleton.parents.begin(), skeleton.parents.end());
  at::Tensor offsets = torch::zeros({1, j, 3});
  auto o = offsets.accessor<float, 3>();
  for (int64_t joint = 0; joint < j; ++joint) {
    for (int k = 0; k < 3; ++k) o[0][joint][k] = static_cast<float>(skeleton.offsets[static_cast<size_t>(joint)][k]);
  }
  return make_skeleton_inputs(torch::tensor(parents, torch::kInt64).view({1, j}), offsets,
                              torch::ones({1, j}, torch::kBool), joint_embeddings.unsqueeze(0));
}

}  // namespace nec::diffusion

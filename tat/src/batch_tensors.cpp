// Batch -> tensors.
#include "nec/tat/batch_tensors.h"

#include <torch/torch.h>

#include <cstdint>
#include <stdexcept>
#include <vector>

namespace nec::tat {
namespace {

// Copies a vector into a new tensor of `shape`; checks the element count.
template <typename T>
at::Tensor copy_to_tensor(const std::vector<T>& values, at::IntArrayRef shape, at::ScalarType type,
                          const char* what) {
  int64_t expected = 1;
  for (int64_t d : shape) expected *= d;
  if (static_cast<int64_t>(values.size()) != expected) {
    throw std::invalid_argument(std::string("to_tensors: ") + what + " has " + std::to_string(values.size()) +
                                " values, its shape needs " + std::to_string(expected));
  }
  // from_blob does not own the memory: clone before the vector goes.
  return torch::from_blob(const_cast<T*>(values.data()), shape, torch::TensorOptions().dtype(type)).clone();
}

}  // namespace

BatchTensors BatchTensors::to(const c10::Device& device) const {
  return {features.to(device), joint_mask.to(device), frame_mask.to(device), parents.to(device), offsets.to(device)};
}

BatchTensors BatchTensors::items(int64_t begin, int64_t count) const {
  return {features.narrow(0, begin, count), joint_mask.narrow(0, begin, count), frame_mask.narrow(0, begin, count),
          parents.narrow(0, begin, count), offsets.narrow(0, begin, count)};
}

BatchTensors to_tensors(const Batch& batch) {
  const int64_t b = batch.size, t = batch.frames, j = batch.max_joints;
  BatchTensors out;
  out.features = copy_to_tensor(batch.features, {b, t, j, 9}, torch::kFloat32, "features");
  out.joint_mask = copy_to_tensor(batch.joint_mask, {b, j}, torch::kUInt8, "joint_mask").to(torch::kBool);
  out.frame_mask = copy_to_tensor(batch.frame_mask, {b, t}, torch::kUInt8, "frame_mask").to(torch::kBool);
  out.parents = copy_to_tensor(batch.parents, {b, j}, torch::kInt32, "parents").to(torch::kInt64);
  out.offsets = copy_to_tensor(batch.offsets, {b, j, 3}, torch::kFloat32, "offsets");
  return out;
}

}  // namespace nec::tat

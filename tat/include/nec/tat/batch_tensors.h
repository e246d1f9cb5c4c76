// Dataset batches (corpus/batch.h, plain arrays) as torch tensors.
//
//   BatchLoader loader(cache, Split::Train, options);
//   BatchTensors x = to_tensors(loader.next()).to(torch::kCUDA);
//   // x.features (B, T, J, 9), x.joint_mask (B, J), ...
//
// The tensors own their memory (copied from the batch), so the batch may go.
#pragma once

#include "nec/corpus/batch.h"

#include <ATen/core/Tensor.h>
#include <c10/core/Device.h>

namespace nec::tat {

struct BatchTensors {
  at::Tensor features;    // (B, T, J, 9) float32, zero where masked
  at::Tensor joint_mask;  // (B, J) bool, true for real joints
  at::Tensor frame_mask;  // (B, T) bool, true for real frames
  at::Tensor parents;     // (B, J) int64, -1 for the root and padding
  at::Tensor offsets;     // (B, J, 3) float32 rest offsets, zero for padding

  BatchTensors to(const c10::Device& device) const;
  // Items [begin, begin + count) of every tensor (views, no copy).
  BatchTensors items(int64_t begin, int64_t count) const;
};

BatchTensors to_tensors(const Batch& batch);

}  // namespace nec::tat

// Batched matrix products split over the intra-op threads.
//
//   at::Tensor scores = batched_matmul(queries, keys);   // (G, N, K) x (G, K, M) -> (G, N, M)
//
// The same product as torch::bmm, with gradients. ATen 1.13 (Debian's) runs a
// bmm of matrices larger than 400 multiply-adds as one BLAS call per matrix,
// in a loop on one thread; attention over the many short sequences of a
// factorized model (a frame's 24 joints, a joint's 120 frames) spends most of
// its time there. On the CPU with two or more intra-op threads this splits
// the batch over them (the forward and both backward products); elsewhere it
// is torch::bmm.
#pragma once

#include <ATen/core/Tensor.h>

namespace nec::layers {

at::Tensor batched_matmul(const at::Tensor& a, const at::Tensor& b);

}  // namespace nec::layers

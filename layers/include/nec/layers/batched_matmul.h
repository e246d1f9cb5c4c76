// Batched matrix products split over the intra-op threads.
//
//   at::Tensor scores = batched_matmul(queries, keys);   // (G, N, K) x (G, K, M) -> (G, N, M)
//
// The same product as torch::bmm, with gradients, on any number of threads.
// ATen 1.13 (Debian's) runs a bmm of matrices larger than 400 multiply-adds
// as one BLAS call per matrix, through several dispatched ops each, in a loop
// on one thread; attention over the many short sequences of a factorized
// model (a frame's 24 joints, a joint's 120 frames) spends most of its time
// there. On the CPU, float32 products whose right operand is small run a
// vectorized loop over the batch, split over the intra-op threads (2.5-3.5x
// faster than bmm on one thread, docs/benchmarks.md); larger ones split
// bmm's loop over the threads; elsewhere (GPU, other types) it is torch::bmm.
// Results equal bmm's up to float rounding (another summation order).
#pragma once

#include <ATen/core/Tensor.h>

namespace nec::layers {

at::Tensor batched_matmul(const at::Tensor& a, const at::Tensor& b);

}  // namespace nec::layers

// Compiled with OpenMP (layers/CMakeLists.txt): Debian's LibTorch implements
// at::parallel_for inline in its headers with OpenMP pragmas, so without
// -fopenmp here it would run on one thread.
#include "nec/layers/batched_matmul.h"

#include <ATen/ATen.h>
#include <ATen/Parallel.h>
#include <ATen/ThreadLocalState.h>
#include <torch/autograd.h>

namespace nec::layers {
namespace {

bool worth_splitting(const at::Tensor& a) {
  return a.device().is_cpu() && !at::in_parallel_region() && at::get_num_threads() > 1 && a.size(0) > 1;
}

// a (G, N, K) x b (G, K, M) -> (G, N, M), each thread a contiguous run of the G products.
at::Tensor split_product(const at::Tensor& a, const at::Tensor& b) {
  const at::Tensor lhs = a.detach(), rhs = b.detach();  // the threads record nothing
  at::Tensor out = at::empty({lhs.size(0), lhs.size(1), rhs.size(2)}, lhs.options());
  const at::ThreadLocalState caller;  // grad and inference mode: the threads write as the caller would
  at::parallel_for(0, lhs.size(0), 1, [&](int64_t begin, int64_t end) {
    const at::ThreadLocalStateGuard same_state(caller);
    at::Tensor part = out.narrow(0, begin, end - begin);
    at::bmm_out(part, lhs.narrow(0, begin, end - begin), rhs.narrow(0, begin, end - begin));
  });
  return out;
}

struct SplitBatchedMatmul : public torch::autograd::Function<SplitBatchedMatmul> {
  static at::Tensor forward(torch::autograd::AutogradContext* ctx, const at::Tensor& a, const at::Tensor& b) {
    ctx->save_for_backward({a, b});
    return split_product(a, b);
  }

  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const torch::autograd::variable_list saved = ctx->get_saved_variables();
    const at::Tensor grad = grads[0].contiguous();
    at::Tensor grad_a, grad_b;
    if (ctx->needs_input_grad(0)) grad_a = split_product(grad, saved[1].transpose(1, 2));
    if (ctx->needs_input_grad(1)) grad_b = split_product(saved[0].transpose(1, 2), grad);
    return {grad_a, grad_b};
  }
};

}  // namespace

at::Tensor batched_matmul(const at::Tensor& a, const at::Tensor& b) {
  if (!worth_splitting(a)) return at::bmm(a, b);
  TORCH_CHECK(a.dim() == 3 && b.dim() == 3 && a.size(0) == b.size(0) && a.size(2) == b.size(1),
              "batched_matmul: (G, N, K) x (G, K, M) expected, got ", a.sizes(), " x ", b.sizes());
  return SplitBatchedMatmul::apply(a, b);
}

}  // namespace nec::layers

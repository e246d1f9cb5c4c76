// Compiled with OpenMP (layers/CMakeLists.txt): Debian's LibTorch implements
// at::parallel_for inline in its headers with OpenMP pragmas, so without
// -fopenmp here it would run on one thread. Compiled with -O3, which lets the
// compiler vectorize the small-matrix loop.
#include "nec/layers/batched_matmul.h"

#include <ATen/ATen.h>
#include <ATen/Parallel.h>
#include <ATen/ThreadLocalState.h>
#include <torch/autograd.h>

#include <algorithm>
#include <cstring>

namespace nec::layers {
namespace {

// The small-matrix loop runs where the right operand of one product fits in
// the fastest caches (64 KiB of floats): there a product of a few dozen rows
// costs ATen's bmm one BLAS call through several dispatched ops per matrix,
// dearer than the multiply-adds; above it BLAS's blocking wins.
constexpr int64_t kSmallRightOperandFloats = 16384;
// Multiply-adds a thread takes at least at once: fewer cost more to hand out than to do.
constexpr int64_t kMultiplyAddsPerTask = 32768;

bool is_small(const at::Tensor& a, const at::Tensor& b) {
  return a.device().is_cpu() && a.scalar_type() == at::kFloat && b.scalar_type() == at::kFloat &&
         b.size(1) * b.size(2) <= kSmallRightOperandFloats;
}

bool worth_splitting(const at::Tensor& a) {
  return a.device().is_cpu() && !at::in_parallel_region() && at::get_num_threads() > 1 && a.size(0) > 1;
}

// Where a matrix of a batch lies: element (g, r, c) at data[g * group + r * row + c * column].
struct Strides {
  int64_t group, row, column;
};

Strides strides_of(const at::Tensor& t) { return {t.stride(0), t.stride(1), t.stride(2)}; }

// c (n x m, contiguous) = a (n x k, any strides) b (k x m, unit column
// stride) for `groups` matrices each. Row i of c accumulates a[i][p] * row p
// of b: the inner loop runs over contiguous floats of b and c and vectorizes,
// and a transposed a (a backward pass's) is read in place; each element of c
// sums its products in the order p = 0, 1, ..., whatever the thread count or
// the batch. Built for AVX2 + FMA too where the compiler can (the CPU picks at
// load time).
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void small_products(const float* a, Strides sa, const float* b, Strides sb, float* c, int64_t groups, int64_t n,
                    int64_t k, int64_t m) {
  for (int64_t g = 0; g < groups; ++g) {
    const float* a_g = a + g * sa.group;
    const float* b_g = b + g * sb.group;
    float* c_g = c + g * n * m;
    for (int64_t i = 0; i < n; ++i) {
      float* c_row = c_g + i * m;
      std::fill(c_row, c_row + m, 0.0f);
      for (int64_t p = 0; p < k; ++p) {
        const float scale = a_g[i * sa.row + p * sa.column];
        const float* b_row = b_g + p * sb.row;
        for (int64_t j = 0; j < m; ++j) c_row[j] += scale * b_row[j];
      }
    }
  }
}

// Splits groups [0, count) over the intra-op threads (one task when called
// from inside a parallel region), carrying the caller's grad and inference
// mode into them.
template <typename Run>
void over_groups(int64_t count, int64_t grain, const Run& run) {
  const at::ThreadLocalState caller;
  at::parallel_for(0, count, grain, [&](int64_t begin, int64_t end) {
    const at::ThreadLocalStateGuard same_state(caller);
    run(begin, end);
  });
}

// a (G, N, K) x b (G, K, M) -> (G, N, M), without recording gradients.
at::Tensor product(const at::Tensor& a, const at::Tensor& b) {
  const at::Tensor lhs = a.detach(), rhs = b.detach();
  const int64_t groups = lhs.size(0), n = lhs.size(1), k = lhs.size(2), m = rhs.size(2);
  if (is_small(lhs, rhs)) {
    // The right operand needs contiguous rows (a transposed one is small: copied); the left is read in place.
    const at::Tensor right = rhs.stride(2) == 1 ? rhs : rhs.contiguous();
    const Strides sa = strides_of(lhs), sb = strides_of(right);
    at::Tensor out = at::empty({groups, n, m}, lhs.options());
    const float* a_data = lhs.data_ptr<float>();
    const float* b_data = right.data_ptr<float>();
    float* c_data = out.data_ptr<float>();
    const int64_t grain = std::max<int64_t>(1, kMultiplyAddsPerTask / std::max<int64_t>(1, n * k * m));
    over_groups(groups, grain, [&](int64_t begin, int64_t end) {
      small_products(a_data + begin * sa.group, sa, b_data + begin * sb.group, sb, c_data + begin * n * m,
                     end - begin, n, k, m);
    });
    return out;
  }
  if (!worth_splitting(lhs)) return at::bmm(lhs, rhs);
  at::Tensor out = at::empty({groups, n, m}, lhs.options());
  over_groups(groups, 1, [&](int64_t begin, int64_t end) {
    at::Tensor part = out.narrow(0, begin, end - begin);
    at::bmm_out(part, lhs.narrow(0, begin, end - begin), rhs.narrow(0, begin, end - begin));
  });
  return out;
}

struct BatchedMatmul : public torch::autograd::Function<BatchedMatmul> {
  static at::Tensor forward(torch::autograd::AutogradContext* ctx, const at::Tensor& a, const at::Tensor& b) {
    ctx->save_for_backward({a, b});
    return product(a, b);
  }

  static torch::autograd::variable_list backward(torch::autograd::AutogradContext* ctx,
                                                 torch::autograd::variable_list grads) {
    const torch::autograd::variable_list saved = ctx->get_saved_variables();
    const at::Tensor& grad = grads[0];
    at::Tensor grad_a, grad_b;
    if (ctx->needs_input_grad(0)) grad_a = product(grad, saved[1].transpose(1, 2));
    if (ctx->needs_input_grad(1)) grad_b = product(saved[0].transpose(1, 2), grad);
    return {grad_a, grad_b};
  }
};

}  // namespace

at::Tensor batched_matmul(const at::Tensor& a, const at::Tensor& b) {
  TORCH_CHECK(a.dim() == 3 && b.dim() == 3 && a.size(0) == b.size(0) && a.size(2) == b.size(1),
              "batched_matmul: (G, N, K) x (G, K, M) expected, got ", a.sizes(), " x ", b.sizes());
  if (!is_small(a, b) && !worth_splitting(a)) return at::bmm(a, b);
  return BatchedMatmul::apply(a, b);
}

}  // namespace nec::layers

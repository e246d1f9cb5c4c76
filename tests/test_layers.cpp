// layers/: batched_matmul against torch::bmm (values and both gradients, on
// two threads, with a transposed operand and an odd batch; small operands,
// which run nec's own loop, and large ones, which split bmm), and the
// multi-head attention against the formula head by head, with a masked key.
#include "nec/layers/batched_matmul.h"
#include "nec/layers/transformer.h"

#include <ATen/Parallel.h>
#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

namespace nec {
namespace {

double max_difference(const at::Tensor& a, const at::Tensor& b) { return (a - b).abs().max().item<double>(); }

class TwoThreads : public ::testing::Test {
 protected:
  void SetUp() override {
    threads_ = at::get_num_threads();
    at::set_num_threads(2);
    torch::manual_seed(7);
  }
  void TearDown() override { at::set_num_threads(threads_); }

 private:
  int threads_ = 1;
};

TEST_F(TwoThreads, BatchedMatmulIsBmmWithItsGradients) {
  const at::Tensor a = torch::randn({7, 24, 16}, torch::requires_grad());
  const at::Tensor b_storage = torch::randn({7, 20, 16}, torch::requires_grad());
  const at::Tensor b = b_storage.transpose(1, 2);  // (7, 16, 20), not contiguous
  const at::Tensor weights = torch::randn({7, 24, 20});

  const at::Tensor ours = layers::batched_matmul(a, b);
  const auto [grad_a, grad_b] = [&] {
    const auto g = torch::autograd::grad({(ours * weights).sum()}, {a, b_storage});
    return std::pair{g[0], g[1]};
  }();
  const at::Tensor reference = torch::bmm(a, b);
  const auto g = torch::autograd::grad({(reference * weights).sum()}, {a, b_storage});

  EXPECT_LT(max_difference(ours, reference), 1e-5);
  EXPECT_LT(max_difference(grad_a, g[0]), 1e-5);
  EXPECT_LT(max_difference(grad_b, g[1]), 1e-5);
  EXPECT_GT(grad_b.abs().max().item<double>(), 0.1);  // the gradient reached the strided operand
}

TEST_F(TwoThreads, BatchedMatmulGradientOfOneOperandOnly) {
  const at::Tensor a = torch::randn({5, 3, 4});
  const at::Tensor b = torch::randn({5, 4, 6}, torch::requires_grad());
  const at::Tensor grad = torch::autograd::grad({layers::batched_matmul(a, b).sum()}, {b})[0];
  // d/db sum(a b) = a^T 1: each column of b gets the row sums of a's columns.
  const at::Tensor expected = a.sum(1).unsqueeze(-1).expand({5, 4, 6});
  EXPECT_LT(max_difference(grad, expected), 1e-5);
}

TEST_F(TwoThreads, BatchedMatmulWithoutGradientsInInferenceModeAndOnOneThread) {
  const at::Tensor a = torch::randn({9, 30, 8}), b = torch::randn({9, 8, 30});
  {
    torch::NoGradGuard no_grad;
    EXPECT_LT(max_difference(layers::batched_matmul(a, b), torch::bmm(a, b)), 1e-5);
  }
  {
    c10::InferenceMode inference;  // as the samplers run: the threads write inference tensors
    const at::Tensor x = torch::randn({9, 30, 8}), y = torch::randn({9, 8, 30});
    EXPECT_LT(max_difference(layers::batched_matmul(x, y), torch::bmm(x, y)), 1e-5);
  }
  at::set_num_threads(1);
  EXPECT_LT(max_difference(layers::batched_matmul(a, b), torch::bmm(a, b)), 1e-5);
}

TEST_F(TwoThreads, BatchedMatmulOfLargeOperandsIsBmmWithItsGradients) {
  // A right operand of 200 x 100 floats is above the small-product loop's limit: bmm split over the threads.
  const at::Tensor a = torch::randn({3, 8, 200}, torch::requires_grad());
  const at::Tensor b = torch::randn({3, 200, 100}, torch::requires_grad());
  const at::Tensor ours = layers::batched_matmul(a, b);
  const auto g = torch::autograd::grad({ours.pow(2).sum()}, {a, b});
  const at::Tensor reference = torch::bmm(a, b);
  const auto expected = torch::autograd::grad({reference.pow(2).sum()}, {a, b});
  EXPECT_LT(max_difference(ours, reference), 1e-4);
  EXPECT_LT(max_difference(g[0], expected[0]), 1e-3);
  EXPECT_LT(max_difference(g[1], expected[1]), 1e-3);
}

TEST_F(TwoThreads, SmallProductsDoNotDependOnTheThreadCountOrTheBatch) {
  // Each product sums in one order whatever the threads or the other matrices: a sample's attention is the same
  // alone and in a batch, on one thread and on two.
  const at::Tensor a = torch::randn({64, 23, 32}), b = torch::randn({64, 32, 23});
  const at::Tensor two_threads = layers::batched_matmul(a, b);
  const at::Tensor one_item = layers::batched_matmul(a.narrow(0, 5, 1), b.narrow(0, 5, 1));
  at::set_num_threads(1);
  const at::Tensor one_thread = layers::batched_matmul(a, b);
  EXPECT_TRUE(torch::equal(two_threads, one_thread));
  EXPECT_TRUE(torch::equal(two_threads.narrow(0, 5, 1), one_item));
  EXPECT_LT(max_difference(one_thread, torch::bmm(a, b)), 1e-4);
}

TEST_F(TwoThreads, AttentionIsTheFormulaPerHeadAndIgnoresMaskedKeys) {
  const int64_t batch = 3, tokens = 5, dim = 8, heads = 2, head_dim = dim / heads;
  const at::Tensor qkv = torch::randn({batch, tokens, 3 * dim});
  at::Tensor mask = torch::ones({batch, tokens}, torch::kBool);
  mask[1][4] = false;
  const at::Tensor out = layers::multi_head_attention(qkv, heads, layers::padding_bias(mask));
  ASSERT_EQ(out.sizes(), (std::vector<int64_t>{batch, tokens, dim}));
  for (int64_t item = 0; item < batch; ++item) {
    const int64_t keys = item == 1 ? tokens - 1 : tokens;
    for (int64_t h = 0; h < heads; ++h) {
      const at::Tensor q = qkv[item].narrow(1, h * head_dim, head_dim);
      const at::Tensor k = qkv[item].narrow(1, dim + h * head_dim, head_dim).narrow(0, 0, keys);
      const at::Tensor v = qkv[item].narrow(1, 2 * dim + h * head_dim, head_dim).narrow(0, 0, keys);
      const at::Tensor expected = torch::softmax(q.matmul(k.t()) / std::sqrt(static_cast<double>(head_dim)), -1).matmul(v);
      EXPECT_LT(max_difference(out[item].narrow(1, h * head_dim, head_dim), expected), 1e-5) << item << " " << h;
    }
  }
}

}  // namespace
}  // namespace nec

// Residual quantizer: nearest codes, EMA learning, dead-code reset, masks, dropout, eval mode.
#include "nec/tat/quantizer.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace nec {
namespace {

using tat::QuantizerConfig;
using tat::QuantizerOutput;
using tat::ResidualQuantizer;

QuantizerConfig small_config(int64_t layers, int64_t codes, int64_t dim) {
  QuantizerConfig config;
  config.layers = layers;
  config.codebook_size = codes;
  config.code_dim = dim;
  config.quantize_dropout = 0.0;
  return config;
}

at::Tensor buffer(ResidualQuantizer& rvq, const std::string& name) { return rvq->named_buffers()[name]; }

// One training step of the quantizer alone: a forward, then the step's EMA update.
QuantizerOutput train_step(ResidualQuantizer& rvq, const at::Tensor& latent, const at::Tensor& mask = {}) {
  QuantizerOutput out = rvq->forward(latent, mask);
  rvq->update_codebooks();
  return out;
}

// Copies of every buffer, by name.
std::vector<std::pair<std::string, at::Tensor>> snapshot(ResidualQuantizer& rvq) {
  std::vector<std::pair<std::string, at::Tensor>> out;
  for (const auto& item : rvq->named_buffers()) out.emplace_back(item.key(), item.value().clone());
  return out;
}

TEST(TatQuantizer, ConfigValidation) {
  EXPECT_NO_THROW(QuantizerConfig{}.validate());
  auto expect_bad = [](QuantizerConfig config, const std::string& field) {
    try {
      config.validate();
      ADD_FAILURE() << "accepted a bad " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  QuantizerConfig c;
  c.layers = 0;
  expect_bad(c, "layers");
  c = {};
  c.ema_decay = 1.0;
  expect_bad(c, "ema_decay");
  c = {};
  c.quantize_dropout = 1.5;
  expect_bad(c, "quantize_dropout");
  c = {};
  c.dead_code_threshold = -1;
  expect_bad(c, "dead_code_threshold");
  EXPECT_THROW(ResidualQuantizer rejected(c), std::invalid_argument);
}

TEST(TatQuantizer, PicksNearestCodesOnAHandBuiltCodebook) {
  ResidualQuantizer rvq(small_config(2, 3, 2));
  {
    torch::NoGradGuard no_grad;
    buffer(rvq, "codebooks").copy_(torch::tensor({0.f, 0.f, 10.f, 0.f, 0.f, 10.f,  // layer 0
                                                  0.f, 0.f, 1.f, 0.f, 0.f, 1.f})  // layer 1
                                       .view({2, 3, 2}));
    buffer(rvq, "initialized").fill_(true);
  }
  rvq->eval();
  const at::Tensor latent = torch::tensor({10.9f, 0.1f, 0.2f, 9.1f}).view({2, 2});
  const QuantizerOutput q = rvq->forward(latent);
  // Row 0: (10, 0) then residual (0.9, 0.1) -> (1, 0). Row 1: (0, 10) then residual (0.2, -0.9) -> (0, 0).
  EXPECT_TRUE(torch::equal(q.codes, torch::tensor({1, 1, 2, 0}, torch::kLong).view({2, 2}))) << q.codes;
  EXPECT_TRUE(torch::allclose(q.quantized, torch::tensor({11.f, 0.f, 0.f, 10.f}).view({2, 2}))) << q.quantized;
  // Layer 0 uses two codes equally often (perplexity 2), layer 1 two codes too.
  EXPECT_NEAR(q.perplexity[0].item<double>(), 2.0, 1e-5);
  EXPECT_NEAR(q.perplexity[1].item<double>(), 2.0, 1e-5);
  // codes_to_latent ignores -1 (a layer skipped by dropout).
  const at::Tensor partial = rvq->codes_to_latent(torch::tensor({1, -1, -1, 2}, torch::kLong).view({2, 2}));
  EXPECT_TRUE(torch::allclose(partial, torch::tensor({10.f, 0.f, 0.f, 1.f}).view({2, 2}))) << partial;
  const at::Tensor first_layer = rvq->codes_to_latent(torch::tensor({2}, torch::kLong).view({1, 1}));
  EXPECT_TRUE(torch::allclose(first_layer, torch::tensor({0.f, 10.f}).view({1, 2})));
  EXPECT_THROW(rvq->codes_to_latent(torch::tensor({3, 0}, torch::kLong).view({1, 2})), std::invalid_argument);
  EXPECT_THROW(rvq->codes_to_latent(torch::zeros({1, 3}, torch::kLong)), std::invalid_argument);
}

TEST(TatQuantizer, MoreLayersReconstructBetterAfterEmaSteps) {
  torch::manual_seed(0);
  ResidualQuantizer rvq(small_config(4, 32, 8));
  const at::Tensor data = torch::randn({1024, 8});
  for (int step = 0; step < 30; ++step) train_step(rvq, data);
  rvq->eval();
  const QuantizerOutput q = rvq->forward(data);
  double previous = data.pow(2).mean().item<double>();
  std::printf("mean squared error by layers used: 0: %.4f", previous);
  for (int64_t used = 1; used <= 4; ++used) {
    const double error = (data - rvq->codes_to_latent(q.codes.narrow(1, 0, used))).pow(2).mean().item<double>();
    std::printf(", %lld: %.4f", static_cast<long long>(used), error);
    EXPECT_LT(error, 0.9 * previous) << "layers " << used;
    previous = error;
  }
  std::printf("\n");
  EXPECT_TRUE(torch::allclose(rvq->codes_to_latent(q.codes), q.quantized, 1e-5, 1e-5));
}

TEST(TatQuantizer, EmaMovesCodesTowardTheData) {
  torch::manual_seed(1);
  QuantizerConfig config = small_config(1, 4, 3);
  config.ema_decay = 0.8;
  config.dead_code_threshold = 0.0;  // no resets: only the EMA moves codes
  ResidualQuantizer rvq(config);
  const at::Tensor a = torch::tensor({5.f, 5.f, 5.f}), b = torch::tensor({-5.f, 0.f, 5.f});
  train_step(rvq, a + 0.1 * torch::randn({64, 3}));  // seeds the codebook near a
  auto nearest_to_b = [&] { return (buffer(rvq, "codebooks")[0] - b).norm(2, 1).min().item<double>(); };
  const double start = nearest_to_b();
  std::vector<double> distances;
  for (int step = 0; step < 20; ++step) {
    train_step(rvq, b + 0.1 * torch::randn({64, 3}));
    distances.push_back(nearest_to_b());
  }
  std::printf("distance of the nearest code to the new data: %.3f -> %.3f -> %.3f\n", start, distances[0],
              distances.back());
  EXPECT_GT(start, 5.0);
  EXPECT_LT(distances[0], start);
  EXPECT_LT(distances.back(), 0.1);
}

TEST(TatQuantizer, EmaUpdateMatchesItsClosedForm) {
  // One layer of two codes with known EMA state; one batch of four kept rows and one masked row.
  QuantizerConfig config = small_config(1, 2, 2);
  config.ema_decay = 0.75;
  config.dead_code_threshold = 0.0;
  ResidualQuantizer rvq(config);
  {
    torch::NoGradGuard no_grad;
    buffer(rvq, "codebooks").copy_(torch::tensor({0.f, 0.f, 4.f, 4.f}).view({1, 2, 2}));
    buffer(rvq, "ema_counts").copy_(torch::tensor({2.f, 6.f}).view({1, 2}));
    buffer(rvq, "ema_sums").copy_(torch::tensor({0.f, 0.f, 24.f, 24.f}).view({1, 2, 2}));
    buffer(rvq, "initialized").fill_(true);
  }
  const at::Tensor rows = torch::tensor({1.f, 0.f, -1.f, 1.f, 3.f, 5.f, 5.f, 3.f, 100.f, 100.f}).view({5, 2});
  const at::Tensor mask = torch::tensor({1, 1, 1, 1, 0}, torch::kBool);
  const QuantizerOutput q = rvq->forward(rows, mask);
  EXPECT_TRUE(torch::equal(q.codes.squeeze(1).narrow(0, 0, 4), torch::tensor({0, 0, 1, 1}, torch::kLong)));
  EXPECT_TRUE(torch::equal(buffer(rvq, "codebooks")[0][1], torch::tensor({4.f, 4.f})))
      << "the EMA moves in update_codebooks(), not in forward";
  ASSERT_TRUE(rvq->update_codebooks());
  // counts' = 0.75 c + 0.25 n = (1.5 + 0.5, 4.5 + 0.5); sums' = 0.75 s + 0.25 (sum of the code's rows).
  const double counts[2] = {0.75 * 2 + 0.25 * 2, 0.75 * 6 + 0.25 * 2};
  const double sums[2][2] = {{0.25 * 0.0, 0.25 * 1.0}, {0.75 * 24 + 0.25 * 8, 0.75 * 24 + 0.25 * 8}};
  const double total = counts[0] + counts[1], epsilon = 1e-5;
  double largest = 0.0;
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(buffer(rvq, "ema_counts")[0][k].item<double>(), counts[k], 1e-6);
    const double smoothed = (counts[k] + epsilon) / (total + 2 * epsilon) * total;  // Laplace smoothing
    for (int c = 0; c < 2; ++c) {
      const double expected = sums[k][c] / smoothed;
      const double got = buffer(rvq, "codebooks")[0][k][c].item<double>();
      largest = std::max(largest, std::abs(got - expected));
      EXPECT_NEAR(buffer(rvq, "ema_sums")[0][k][c].item<double>(), sums[k][c], 1e-6);
    }
  }
  std::printf("largest codebook difference from the closed form: %.3g\n", largest);
  EXPECT_LT(largest, 1e-5);
  EXPECT_FALSE(rvq->update_codebooks()) << "statistics are used once";
}

TEST(TatQuantizer, ResetsDeadCodesToKeptResiduals) {
  torch::manual_seed(2);
  ResidualQuantizer rvq(small_config(1, 8, 4));
  const at::Tensor data = torch::randn({64, 4});
  train_step(rvq, data);  // seeds
  {
    torch::NoGradGuard no_grad;
    buffer(rvq, "codebooks")[0][3].fill_(1000.0f);  // far from everything: never chosen
    buffer(rvq, "ema_sums")[0][3].fill_(0.0f);
    buffer(rvq, "ema_counts")[0][3].fill_(0.0f);
  }
  train_step(rvq, data);
  const at::Tensor code = buffer(rvq, "codebooks")[0][3];
  const double to_data = (data - code).norm(2, 1).min().item<double>();
  std::printf("reset code: distance to the nearest data row %.3g\n", to_data);
  EXPECT_LT(to_data, 1e-5);
  EXPECT_GE(buffer(rvq, "ema_counts")[0][3].item<double>(), rvq->config().dead_code_threshold);
}

TEST(TatQuantizer, SeedsLaterLayersAtResidualsTheFirstLeavesUnexplained) {
  // As many rows as codes: a first layer seeded at data rows explains those rows
  // exactly, so a second layer seeded uniformly from the residuals would get many
  // zero codes (duplicates that never learn anything).
  torch::manual_seed(7);
  QuantizerConfig config = small_config(2, 32, 4);
  config.dead_code_threshold = 0.0;  // seeding alone
  ResidualQuantizer rvq(config);
  train_step(rvq, torch::randn({32, 4}));
  const at::Tensor norms = buffer(rvq, "codebooks")[1].norm(2, 1);
  const int64_t zero_codes = (norms < 1e-6).sum().item<int64_t>();
  std::printf("second-layer codes at zero residuals: %lld of 32\n", static_cast<long long>(zero_codes));
  EXPECT_EQ(zero_codes, 0);
}

TEST(TatQuantizer, MaskedRowsDoNotInfluenceTheCodebooks) {
  QuantizerConfig config = small_config(3, 16, 4);
  config.quantize_dropout = 0.5;
  const at::Tensor data = torch::randn({100, 4});
  const at::Tensor mask = torch::rand({100}) < 0.6;
  const at::Tensor garbage = torch::where(mask.unsqueeze(1), data, 100.0 * torch::randn({100, 4}) + 50.0);
  auto run = [&](const at::Tensor& input) {
    torch::manual_seed(3);
    ResidualQuantizer rvq(config);
    QuantizerOutput q;
    for (int step = 0; step < 5; ++step) q = train_step(rvq, input, mask);
    return std::make_pair(snapshot(rvq), q.commitment_loss.item<double>());
  };
  const auto clean = run(data), dirty = run(garbage);
  for (size_t i = 0; i < clean.first.size(); ++i) {
    const double difference =
        (clean.first[i].second.to(torch::kDouble) - dirty.first[i].second.to(torch::kDouble)).abs().max().item<double>();
    EXPECT_LT(difference, 1e-5) << clean.first[i].first;
  }
  EXPECT_NEAR(clean.second, dirty.second, 1e-6);
}

TEST(TatQuantizer, EvalModeLeavesBuffersUnchangedAndNeverDrops) {
  torch::manual_seed(4);
  QuantizerConfig config = small_config(4, 16, 4);
  config.quantize_dropout = 1.0;
  ResidualQuantizer rvq(config);
  const at::Tensor data = torch::randn({50, 4});
  train_step(rvq, data);
  rvq->eval();
  const auto before = snapshot(rvq);
  for (int i = 0; i < 3; ++i) {
    const QuantizerOutput q = rvq->forward(data);
    EXPECT_TRUE((q.codes >= 0).all().item<bool>());
    EXPECT_TRUE(torch::allclose(rvq->codes_to_latent(q.codes), q.quantized, 1e-5, 1e-5));
  }
  const auto after = snapshot(rvq);
  for (size_t i = 0; i < before.size(); ++i) EXPECT_TRUE(torch::equal(before[i].second, after[i].second)) << before[i].first;
}

TEST(TatQuantizer, QuantizeDropoutUsesOnlyTheFirstLayers) {
  torch::manual_seed(5);
  QuantizerConfig config = small_config(4, 8, 4);
  config.quantize_dropout = 1.0;
  ResidualQuantizer rvq(config);
  std::vector<int> seen(5, 0);
  for (int i = 0; i < 40; ++i) {
    const QuantizerOutput q = rvq->forward(torch::randn({32, 4}));
    const at::Tensor used = (q.codes >= 0).all(0);  // (R) layers used by the whole batch
    const int64_t count = used.sum().item<int64_t>();
    ASSERT_GE(count, 1);
    ++seen[count];
    for (int64_t r = 0; r < 4; ++r) {
      EXPECT_EQ(used[r].item<bool>(), r < count);  // a prefix of the layers
      EXPECT_EQ((q.codes.select(1, r) < 0).all().item<bool>(), r >= count);
      if (r >= count) {
        EXPECT_EQ(q.perplexity[r].item<double>(), 0.0);
      }
    }
  }
  std::printf("batches using 1..4 layers: %d %d %d %d\n", seen[1], seen[2], seen[3], seen[4]);
  EXPECT_GT(seen[1] + seen[2] + seen[3], 0);
}

TEST(TatQuantizer, StraightThroughGradientAndCommitmentLoss) {
  torch::manual_seed(6);
  QuantizerConfig config = small_config(2, 8, 4);
  config.commitment_weight = 0.25;
  ResidualQuantizer rvq(config);
  train_step(rvq, torch::randn({64, 4}));
  rvq->eval();
  const at::Tensor latent = torch::randn({10, 4}).requires_grad_(true);
  const at::Tensor mask = torch::tensor({1, 1, 0, 1, 0, 1, 1, 1, 0, 1}, torch::kBool);
  const QuantizerOutput q = rvq->forward(latent, mask);
  const at::Tensor weights = torch::randn({10, 4});
  (q.quantized * weights).sum().backward();
  EXPECT_TRUE(torch::allclose(latent.grad(), weights));  // identity gradient

  const at::Tensor codes_latent = rvq->codes_to_latent(q.codes);
  const at::Tensor kept_rows = torch::nonzero(mask).squeeze(1);
  const double expected =
      0.25 * (latent.detach() - codes_latent).pow(2).index_select(0, kept_rows).mean().item<double>();
  EXPECT_NEAR(q.commitment_loss.item<double>(), expected, 1e-6);
  latent.grad().zero_();
  q.commitment_loss.backward();
  EXPECT_GT(latent.grad().abs().sum().item<double>(), 0.0);
  EXPECT_EQ(latent.grad().index_select(0, torch::nonzero(~mask).squeeze(1)).abs().sum().item<double>(), 0.0);
}

}  // namespace
}  // namespace nec

// A golden evaluator training step: the C++ step on the synthetic batch of benchmarks/peer_evaluator_step.py
// gives the losses the Python (PyTorch) peer printed for the same inputs, weights, dropout masks and schedule.
#include "nec/evaluator/synthetic.h"
#include "nec/evaluator/training.h"
#include "nec/train/heap.h"
#include "nec/train/optimizer.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace nec {
namespace {

// configs/evaluator_cpu.json with joint embeddings as wide as configs/owo_cpu.json's encoder, as the peer reads them.
evaluator::EvaluatorTrainConfig peer_config() {
  const std::filesystem::path configs = std::filesystem::path(__FILE__).parent_path().parent_path() / "configs";
  evaluator::EvaluatorTrainConfig config = evaluator::read_evaluator_train_config((configs / "evaluator_cpu.json").string());
  std::ifstream owo(configs / "owo_cpu.json");
  config.model.motion.joint_embedding_dim = nlohmann::json::parse(owo).at("encoder").at("dim").get<int64_t>();
  config.validate();
  return config;
}

// `/usr/bin/python3 benchmarks/peer_evaluator_step.py` (Debian python3-torch 1.13.1): the losses of its first two
// steps at 22 and 100 joints. Both sides seed torch with 0, draw the batch, then the weights.
struct PeerRun {
  int64_t joints;
  double losses[2];
};
constexpr PeerRun kPeerRuns[] = {{22, {4.424269199371338, 4.442472457885742}},
                                 {100, {4.231795310974121, 4.238805770874023}}};
// Relative, step by step. Both sides run the same ATen kernels in the same order on one thread, and were seen to
// agree bit for bit; the bounds leave room for another CPU's summation order. Step 1: float rounding of a
// 64 x 64 softmax over sums of thousands of products (~1e-6). Step 2 follows one AdamW update, which moves a
// parameter whose gradient is only rounding noise by the full learning rate (as the tokenizer's golden step).
constexpr double kTolerance[2] = {2e-6, 5e-5};

TEST(EvaluatorPeerStep, FirstTwoLossesEqualThePythonPeers) {
  // As nec and the benchmark: otherwise every step maps and page-faults its large tensors again (3x the time).
  train::keep_large_allocations_in_heap();
  torch::set_num_threads(1);
  const evaluator::EvaluatorTrainConfig config = peer_config();
  double largest = 0.0;
  for (const PeerRun& peer : kPeerRuns) {
    torch::manual_seed(0);
    const evaluator::ContrastiveBatch inputs = evaluator::synthetic_contrastive_batch(
        config.batch_size, config.data.window_frames, peer.joints, config.model.motion.joint_embedding_dim);
    evaluator::Evaluator model(config.model);
    auto optimizer = train::make_adamw(model->parameters(), config.optimizer);
    for (int64_t step = 1; step <= 2; ++step) {
      const double loss = evaluator::synthetic_evaluator_train_step(*model, *optimizer, inputs, config, step);
      const double expected = peer.losses[step - 1];
      const double relative = std::abs(loss - expected) / expected;
      largest = std::max(largest, relative);
      std::printf("%lld joints, step %lld: C++ %.9f, Python peer %.9f, relative difference %.2g\n",
                  static_cast<long long>(peer.joints), static_cast<long long>(step), loss, expected, relative);
      EXPECT_LT(relative, kTolerance[step - 1]) << peer.joints << " joints, step " << step;
    }
  }
  std::printf("largest relative difference: %.2g\n", largest);
}

}  // namespace
}  // namespace nec

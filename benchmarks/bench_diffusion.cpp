// Cost of the diffusion model on the CPU.
//
//   bench_diffusion [benchmark flags]
//
// - BM_Sample4s/batch:B: one call of diffusion::sample_motions for B samples
//   of a 4-s motion (120 frames at 30 fps) at 50 DDIM steps with guidance 2.5
//   (both halves as one batch), on a 24-joint skeleton, with
//   configs/diffusion_pose_cpu.json's denoiser and random weights (the cost
//   does not depend on them). Counter peak_rss_mb: the process's peak
//   resident memory after the run. Goal: B = 1 in < 3 s on 2 cores.
// - BM_Attention/joints:J/frames:T/full:F: the attention of one layer over
//   J x T joint tokens (width 64, 4 heads): factorized (F = 0: the joints of
//   each frame, then each joint across frames) or full spatio-temporal
//   attention over all J x T tokens (F = 1; computed 1,024 queries at a time
//   so that its score matrix fits in memory; the work is the same).
// Each runs 3 repetitions of one iteration.
#include "nec/diffusion/denoiser.h"
#include "nec/diffusion/sampling.h"
#include "nec/diffusion/training.h"
#include "nec/layers/transformer.h"
#include "nec/train/heap.h"

#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <torch/torch.h>

#include <cmath>
#include <string>
#include <thread>
#include <vector>

namespace {

constexpr int kRepetitions = 3;
constexpr int64_t kJoints = 24, kFrames = 120, kDim = 64, kHeads = 4, kQueryChunk = 1024;

// configs/diffusion_pose_cpu.json's denoiser with every weight random (the zero-initialised gates too).
struct RandomDenoiser {
  nec::diffusion::MotionDenoiser model{nullptr};
  nec::diffusion::SkeletonInputs skeleton;
  at::Tensor caption;

  RandomDenoiser() {
    nec::diffusion::DenoiserConfig config =
        nec::diffusion::read_diffusion_train_config(std::string(NEC_SOURCE_DIR) + "/configs/diffusion_pose_cpu.json").model;
    config.skeleton_dim = 64;
    torch::manual_seed(0);
    model = nec::diffusion::MotionDenoiser(config);
    torch::NoGradGuard no_grad;
    for (at::Tensor& p : model->parameters()) p.normal_(0.0, 0.05);
    model->eval();
    // A chain body with two branches every few joints, like a small biped.
    std::vector<int64_t> parents{-1};
    for (int64_t j = 1; j < kJoints; ++j) parents.push_back(j % 6 == 1 ? 0 : j - 1);
    skeleton = nec::diffusion::make_skeleton_inputs(torch::tensor(parents).view({1, kJoints}),
                                                    torch::randn({1, kJoints, 3}) * 0.1,
                                                    torch::ones({1, kJoints}, torch::kBool), torch::randn({1, kJoints, 64}));
    caption = torch::randn({1, config.dim});
  }
};

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

void BM_Sample4s(benchmark::State& state) {
  static RandomDenoiser denoiser;
  const nec::diffusion::NoiseSchedule schedule(denoiser.model->config().noise_steps);
  nec::diffusion::DiffusionSamplingOptions options;  // 50 steps, guidance 2.5
  const int samples = static_cast<int>(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(nec::diffusion::sample_motions(*denoiser.model, schedule, denoiser.skeleton,
                                                            denoiser.caption, {kFrames}, samples, options));
  }
  state.counters["peak_rss_mb"] = peak_rss_mb();
  state.counters["motions_per_s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_Attention(benchmark::State& state) {
  const int64_t joints = state.range(0), frames = state.range(1);
  const bool full = state.range(2) == 1;
  torch::manual_seed(0);
  const at::Tensor qkv = torch::randn({frames, joints, 3 * kDim});  // one frame's joints per row
  c10::InferenceMode inference;
  for (auto _ : state) {
    if (!full) {
      const at::Tensor spatial = nec::layers::multi_head_attention(qkv, kHeads, {});
      const at::Tensor temporal = nec::layers::multi_head_attention(qkv.transpose(0, 1).contiguous(), kHeads, {});
      benchmark::DoNotOptimize(spatial);
      benchmark::DoNotOptimize(temporal);
      continue;
    }
    // All J x T tokens attend to all: queries a chunk at a time against every key.
    const int64_t n = joints * frames, head = kDim / kHeads;
    const at::Tensor all = qkv.reshape({n, 3, kHeads, head}).permute({1, 2, 0, 3});  // (3, H, N, Dh)
    const at::Tensor keys = all[1].transpose(-1, -2).contiguous(), values = all[2].contiguous();
    for (int64_t begin = 0; begin < n; begin += kQueryChunk) {
      const at::Tensor queries = all[0].narrow(1, begin, std::min(kQueryChunk, n - begin));
      const at::Tensor scores = torch::matmul(queries, keys) * (1.0 / std::sqrt(static_cast<double>(head)));
      benchmark::DoNotOptimize(torch::matmul(torch::softmax(scores, -1), values));
    }
  }
  state.counters["tokens"] = static_cast<double>(joints * frames);
}

}  // namespace

BENCHMARK(BM_Sample4s)->ArgName("batch")->Arg(1)->Arg(8)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)->Repetitions(kRepetitions);
BENCHMARK(BM_Attention)
    ->ArgNames({"joints", "frames", "full"})
    ->ArgsProduct({{20, 60, 140}, {60, 120, 240}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1)
    ->Repetitions(kRepetitions);

int main(int argc, char** argv) {
  nec::train::keep_large_allocations_in_heap();  // as nec does
  torch::set_num_threads(static_cast<int>(std::thread::hardware_concurrency()));  // every core (2 here)
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

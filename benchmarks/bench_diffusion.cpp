// Cost of the diffusion model on the CPU.
//
//   bench_diffusion [--configs=DIR] [--profile_ops=DIR] [benchmark flags]   # e.g. --benchmark_filter=TrainStep
//
// - BM_Sample4s/batch:B/ddim50:D: one call of diffusion::sample_motions for B
//   samples of a 4-s motion (120 frames at 30 fps), D = 0: generation's
//   defaults (10 DPM-Solver++ steps, quadratic spacing), D = 1: 50 uniform DDIM
//   steps (the sampling before 2026-12-07); guidance 2.5
//   (both halves as one batch), on a 24-joint skeleton, with
//   configs/diffusion_pose_cpu.json's denoiser and random weights (the cost
//   does not depend on them). Counter peak_rss_mb: the process's peak
//   resident memory after the run. Goal: B = 1 in < 3 s on 2 cores.
// - BM_Attention/joints:J/frames:T/full:F: the attention of one layer over
//   J x T joint tokens (width 64, 4 heads): factorized (F = 0: the joints of
//   each frame, then each joint across frames) or full spatio-temporal
//   attention over all J x T tokens (F = 1; computed 1,024 queries at a time
//   so that its score matrix fits in memory; the work is the same).
// - BM_DiffusionTrainStep/stage:S/joints:J/threads:N: what DiffusionTrainer::step
//   does after its batch is drawn (diffusion/synthetic.h): train mode,
//   zero_grad, the denoising loss (with the velocity term in the motion
//   stage), backward, clipping, AdamW at the scheduled rate. S = motion: the
//   temporal blocks on a frozen pose model, DIR/diffusion_motion_cpu.json
//   (batch 4 x 120 frames); S = pose: DIR/diffusion_pose_cpu.json (batch 32 x
//   pose_frames); the model of DIR/diffusion_pose_cpu.json with skeleton_dim =
//   encoder.dim of DIR/owo_cpu.json; DIR is the repository's configs/ unless
//   given. The batch is synthetic: J the widest skeleton (random trees, the
//   other items down to 3/4 of J joints, crops down to half the window),
//   random joint embeddings in place of OwO's, random use-lite caption
//   features in place of the sentence encoder's (neither is read).
//   benchmarks/peer_diffusion_step.py makes the same tensors with the same
//   torch random draws, so its first losses must equal the counters
//   loss_step0 and loss_step1 here. Counters as BM_TatTrainStep (bench_tat):
//   parameters (all of the denoiser's; the peer checks its count against it),
//   trained_parameters (the stage's), loss_step0, loss_step1, step_peak_MiB
//   (peak RSS of one step above the RSS before it, after malloc_trim),
//   rss_peak_MiB. Model, first losses and memory are made once per stage and
//   J, at one thread after torch::manual_seed(0), then 2 untimed steps.
// Each runs 3 repetitions of one iteration (the pose stage's train step: 3 iterations).
#include "nec/diffusion/denoiser.h"
#include "nec/diffusion/sampling.h"
#include "nec/diffusion/synthetic.h"
#include "nec/diffusion/training.h"
#include "nec/layers/transformer.h"
#include "nec/train/heap.h"
#include "train_step_support.h"

#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <torch/torch.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <thread>
#include <vector>

namespace {

constexpr int kRepetitions = 3;
constexpr int64_t kJoints = 24, kFrames = 120, kDim = 64, kHeads = 4, kQueryChunk = 1024;
constexpr uint64_t kSeed = 0;        // torch::manual_seed before inputs and model (as the peer)

// configs/diffusion_pose_cpu.json's denoiser with every weight random (the zero-initialised gates too).
struct RandomDenoiser {
  nec::diffusion::MotionDenoiser model{nullptr};
  nec::diffusion::SkeletonInputs skeleton;
  at::Tensor caption;

  RandomDenoiser() {
    nec::diffusion::DenoiserConfig config =
        nec::diffusion::read_diffusion_train_config(nec::bench::configs_dir() + "/diffusion_pose_cpu.json").model;
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
  nec::diffusion::DiffusionSamplingOptions options;  // generation's defaults, guidance 2.5
  if (state.range(1) == 1) {
    options.steps = 50;
    options.solver = nec::diffusion::DiffusionSolver::kDdim;
    options.spacing = nec::diffusion::TimestepSpacing::kUniform;
  }
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


// ---- Training step ----

using nec::diffusion::DiffusionStage;

// A stage's model, optimizer and one batch, kept across repetitions and thread counts.
struct Trainee {
  DiffusionStage stage = DiffusionStage::kMotion;
  nec::diffusion::DiffusionTrainConfig config;
  nec::diffusion::SyntheticDiffusionBatch inputs;
  nec::diffusion::MotionDenoiser model{nullptr};
  std::unique_ptr<torch::optim::AdamW> optimizer;
  int64_t trained_parameters = 0;
  int64_t steps = 0;  // steps taken (learning-rate schedule position)
  nec::bench::StepRecord record;
};

double train_step(Trainee& t) {
  return nec::diffusion::synthetic_diffusion_train_step(*t.model, *t.optimizer, t.inputs, t.config, t.stage, ++t.steps);
}

Trainee& trainee(DiffusionStage stage, int64_t joints) {
  static std::map<std::pair<DiffusionStage, int64_t>, std::unique_ptr<Trainee>> made;
  std::unique_ptr<Trainee>& slot = made[{stage, joints}];
  if (slot) return *slot;
  slot = std::make_unique<Trainee>();
  Trainee& t = *slot;
  const int threads = torch::get_num_threads();
  torch::set_num_threads(1);
  t.stage = stage;
  t.config = nec::diffusion::synthetic_stage_config(nec::bench::configs_dir(), stage);
  torch::manual_seed(kSeed);
  t.inputs = nec::diffusion::synthetic_diffusion_batch(t.config, stage, joints);
  t.model = nec::diffusion::synthetic_denoiser(t.config, stage, t.inputs);
  const std::vector<at::Tensor> trained = nec::diffusion::trained_parameters(*t.model, stage, t.config.train_pose_model);
  t.optimizer = nec::train::make_adamw(trained, t.config.optimizer);
  for (const at::Tensor& p : trained) t.trained_parameters += p.numel();
  t.record = nec::bench::record_first_steps(t.model->parameters(), [&] { return train_step(t); });
  torch::set_num_threads(threads);
  return t;
}

void BM_DiffusionTrainStep(benchmark::State& state, DiffusionStage stage) {
  const int threads = torch::get_num_threads();
  Trainee& t = trainee(stage, state.range(0));
  torch::set_num_threads(static_cast<int>(state.range(1)));
  for (auto _ : state) benchmark::DoNotOptimize(train_step(t));
  nec::bench::profile_ops_if_asked(std::string("BM_DiffusionTrainStep/stage:") + nec::diffusion::to_string(stage) +
                                       "/joints:" + std::to_string(state.range(0)) + "/threads:" +
                                       std::to_string(state.range(1)),
                                   [&] { train_step(t); }, 1);
  torch::set_num_threads(threads);
  nec::bench::set_step_counters(state, t.record);
  state.counters["trained_parameters"] = static_cast<double>(t.trained_parameters);
}

void register_train_steps() {
  for (const DiffusionStage stage : {DiffusionStage::kMotion, DiffusionStage::kPose}) {
    const std::string name = std::string("BM_DiffusionTrainStep/stage:") + nec::diffusion::to_string(stage);
    benchmark::RegisterBenchmark(name.c_str(), BM_DiffusionTrainStep, stage)
        ->ArgNames({"joints", "threads"})
        ->ArgsProduct({{22, 100}, {1, 2}})
        ->Iterations(stage == DiffusionStage::kPose ? 3 : 1)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime()
        ->MeasureProcessCPUTime()
        ->Repetitions(kRepetitions);
  }
}

}  // namespace

BENCHMARK(BM_Sample4s)->ArgNames({"batch", "ddim50"})->ArgsProduct({{1, 8}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1)->Repetitions(kRepetitions);
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
  benchmark::Initialize(&argc, argv);  // removes the --benchmark_* flags it knows
  for (int i = 1; i < argc; ++i) {
    if (!nec::bench::take_step_flag(argv[i])) {
      std::fprintf(stderr, "bench_diffusion: unknown argument '%s' (--configs=DIR, --profile_ops=DIR or --benchmark_* flags)\n",
                   argv[i]);
      return 2;
    }
  }
  register_train_steps();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

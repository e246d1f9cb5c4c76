// Cost of the tokenizer (TAT) on the CPU: one training step, whole-clip
// encode / decode throughput, and the peak memory of a step.
//
//   bench_tat [--configs=DIR] [--profile_ops=DIR] [benchmark flags]   # e.g. --benchmark_filter=TrainStep
//
// Model: DIR/tat_cpu.json with joint_embedding_dim = encoder.dim of
// DIR/owo_cpu.json (as `nec train tat` sets it from the OwO checkpoint); DIR
// is the repository's configs/ unless given.
// - BM_TatTrainStep/joints:J/threads:N: what TatTrainer::step does after its
//   inputs are made: forward (train mode), reconstruction_loss, zero_grad,
//   backward, clip_grad_norm_, AdamW at the scheduled learning rate. Inputs
//   are a synthetic batch (B = batch_size, T = window_frames, J joints): a
//   random tree per item (parents before children), random rotations, random
//   rest offsets and fixed random joint embeddings (B, J, E) in place of OwO.
//   benchmarks/peer_tat_step.py makes the same tensors with the same torch
//   random draws, so its first losses must equal the counters loss_step0 and
//   loss_step1 here.
// - BM_TatEncodeClip / BM_TatDecodeClip/joints:J/threads:N: encode_clip /
//   decode_clip of a 600-frame random clip (64-frame windows, 16 overlap), in
//   eval mode; counter frames_per_s.
// With --profile_ops=DIR, one more step per training-step benchmark runs under
// the op profiler (train_step_support.h) into DIR/BM_TatTrainStep_joints_J_threads_N.json.
// Counters of the training step: parameters (the peer checks its count
// against it), step_peak_MiB (peak RSS of one step above the RSS before it,
// after malloc_trim) and rss_peak_MiB (the process's peak RSS during that
// step). Model, first losses and memory are made once per J, at one thread.
// Each benchmark runs 5 repetitions (unless --benchmark_repetitions is given)
// of a fixed number of iterations and reports mean, median, stddev, cv, min
// and max over them of the wall-clock time and the process CPU time (all
// threads); --benchmark_out keeps each repetition too.
#include "nec/owo/training.h"
#include "nec/tat/fk.h"
#include "nec/tat/inference.h"
#include "nec/tat/loss.h"
#include "nec/tat/synthetic.h"
#include "nec/tat/tokenizer.h"
#include "nec/tat/training.h"
#include "nec/train/heap.h"
#include "train_step_support.h"

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using nec::tat::BatchTensors;
using nec::tat::Tokenizer;

constexpr uint64_t kSeed = 0;           // torch::manual_seed before inputs and model (as the peer)
constexpr int64_t kClipFrames = 600;    // encode / decode clip length
constexpr int kDefaultRepetitions = 5;

// tat_cpu.json, joint embeddings as wide as owo_cpu.json's encoder.
const nec::tat::TatTrainConfig& train_config() {
  static const nec::tat::TatTrainConfig config = [] {
    nec::tat::TatTrainConfig c = nec::tat::read_tat_train_config(nec::bench::configs_dir() + "/tat_cpu.json");
    c.model.joint_embedding_dim = nec::owo::read_owo_training_config(nec::bench::configs_dir() + "/owo_cpu.json").encoder.dim;
    c.validate();
    return c;
  }();
  return config;
}

// ---- Training step ----

// A model, its optimizer and one batch, kept across repetitions and thread counts.
struct Trainee {
  nec::tat::SyntheticBatch inputs;
  Tokenizer model{nullptr};
  std::unique_ptr<torch::optim::AdamW> optimizer;
  int64_t steps = 0;  // steps taken (learning-rate schedule position)
  nec::bench::StepRecord record;
};

// One step of the peer-comparable loop (tat/synthetic.h) at the next schedule position.
double train_step(Trainee& t) {
  return nec::tat::synthetic_train_step(*t.model, *t.optimizer, t.inputs, train_config(), ++t.steps);
}

// The T of a joint count, made by build(T&, joints) on first use and kept for
// every later benchmark of that size.
template <typename T, typename Build>
T& per_joint_count(int64_t joints, Build build) {
  static std::map<int64_t, std::unique_ptr<T>> made;
  std::unique_ptr<T>& slot = made[joints];
  if (!slot) {
    slot = std::make_unique<T>();
    build(*slot, joints);
  }
  return *slot;
}

void build_trainee(Trainee& t, int64_t joints) {
  const nec::tat::TatTrainConfig& config = train_config();
  const int threads = torch::get_num_threads();
  torch::set_num_threads(1);
  torch::manual_seed(kSeed);
  t.inputs = nec::tat::synthetic_batch(config.batch_size, config.data.window_frames, joints, config.model.joint_embedding_dim);
  t.model = Tokenizer(config.model);
  t.optimizer = nec::train::make_adamw(t.model->parameters(), config.optimizer);
  t.record = nec::bench::record_first_steps(t.model->parameters(), [&] { return train_step(t); });
  torch::set_num_threads(threads);
}

Trainee& trainee(int64_t joints) { return per_joint_count<Trainee>(joints, build_trainee); }

void BM_TatTrainStep(benchmark::State& state) {
  const int64_t joints = state.range(0);
  torch::set_num_threads(static_cast<int>(state.range(1)));
  Trainee& t = trainee(joints);
  for (auto _ : state) benchmark::DoNotOptimize(train_step(t));
  nec::bench::profile_ops_if_asked("BM_TatTrainStep/joints:" + std::to_string(joints) + "/threads:" +
                                       std::to_string(state.range(1)),
                                   [&] { train_step(t); }, 1);
  const nec::tat::TatTrainConfig& config = train_config();
  state.SetItemsProcessed(state.iterations() * config.batch_size * config.data.window_frames);  // frames
  nec::bench::set_step_counters(state, t.record);
}

// ---- Whole-clip encode / decode ----

struct Clip {
  Tokenizer model{nullptr};  // eval mode
  nec::Skeleton skeleton;    // J joints, a random tree with left and right joints (decode faces it forward)
  nec::Features features;    // kClipFrames x J
  at::Tensor embeddings;     // (J, E)
  at::Tensor codes;          // (S, R) of features
};

nec::tat::WindowOptions windows() { return {train_config().data.window_frames, 16}; }

void build_clip(Clip& c, int64_t joints) {
  const nec::tat::TatTrainConfig& config = train_config();
  torch::manual_seed(kSeed);
  const at::Tensor theta = nec::tat::random_features(1, kClipFrames, joints)[0].contiguous();
  c.features.frame_count = static_cast<int>(kClipFrames);
  c.features.joint_count = static_cast<int>(joints);
  c.features.data.assign(theta.data_ptr<float>(), theta.data_ptr<float>() + theta.numel());
  std::mt19937 rng(kSeed);
  std::normal_distribution<double> offset(0.0, 0.1);
  for (int64_t j = 0; j < joints; ++j) {
    const int parent = j == 0 ? -1 : static_cast<int>(std::uniform_int_distribution<int64_t>(0, j - 1)(rng));
    const std::string name = j == 0 ? "Hips" : (j % 2 ? "Left" : "Right") + std::to_string(j);
    c.skeleton.add_joint(name, parent, j == 0 ? nec::Vec3::Zero() : nec::Vec3(offset(rng), offset(rng), offset(rng)),
                         j == 0 ? nec::ChannelLayout::position_rotations(nec::EulerOrder::ZXY)
                                : nec::ChannelLayout::rotations(nec::EulerOrder::ZXY));
  }
  c.embeddings = torch::randn({joints, config.model.joint_embedding_dim});
  c.model = Tokenizer(config.model);
  c.model->eval();
  c.codes = nec::tat::encode_clip(*c.model, c.features, c.embeddings, windows());
}

Clip& clip(int64_t joints) { return per_joint_count<Clip>(joints, build_clip); }

void BM_TatEncodeClip(benchmark::State& state) {
  torch::set_num_threads(static_cast<int>(state.range(1)));
  Clip& c = clip(state.range(0));
  for (auto _ : state) {
    const at::Tensor codes = nec::tat::encode_clip(*c.model, c.features, c.embeddings, windows());
    benchmark::DoNotOptimize(codes.data_ptr());
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kClipFrames), benchmark::Counter::kIsRate);
}

void BM_TatDecodeClip(benchmark::State& state) {
  torch::set_num_threads(static_cast<int>(state.range(1)));
  Clip& c = clip(state.range(0));
  for (auto _ : state) {
    const nec::Features out = nec::tat::decode_clip(*c.model, c.codes, static_cast<int>(kClipFrames), c.embeddings,
                                                    c.skeleton, 30.0, windows());
    benchmark::DoNotOptimize(out.data.data());
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations() * kClipFrames), benchmark::Counter::kIsRate);
}

void register_all() {
  struct Entry {
    const char* name;
    void (*function)(benchmark::State&);
    int64_t iterations_22, iterations_100;  // per repetition, for J = 22 and J = 100
  };
  for (const Entry& e : {Entry{"BM_TatTrainStep", BM_TatTrainStep, 3, 1},
                         Entry{"BM_TatEncodeClip", BM_TatEncodeClip, 4, 1},
                         Entry{"BM_TatDecodeClip", BM_TatDecodeClip, 4, 1}}) {
    for (int64_t joints : {22, 100}) {
      benchmark::RegisterBenchmark(e.name, e.function)
          ->ArgNames({"joints", "threads"})
          ->Args({joints, 1})
          ->Args({joints, 2})
          ->Iterations(joints == 22 ? e.iterations_22 : e.iterations_100)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()            // time: wall clock
          ->MeasureProcessCPUTime()  // cpu_time: all threads of the process
          ->ComputeStatistics("min", nec::bench::smallest)
          ->ComputeStatistics("max", nec::bench::largest)
          ->DisplayAggregatesOnly(true);  // the JSON output keeps every repetition
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  nec::train::keep_large_allocations_in_heap();  // as nec does
  std::vector<char*> args(argv, argv + argc);
  std::string repetitions = "--benchmark_repetitions=" + std::to_string(kDefaultRepetitions);
  bool has_repetitions = false;
  for (char* arg : args) has_repetitions |= std::strncmp(arg, "--benchmark_repetitions", 23) == 0;
  if (!has_repetitions) args.push_back(repetitions.data());
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());  // removes the --benchmark_* flags it knows
  for (int i = 1; i < count; ++i) {
    if (!nec::bench::take_step_flag(args[i])) {
      std::fprintf(stderr, "bench_tat: unknown argument '%s' (--configs=DIR, --profile_ops=DIR or --benchmark_* flags)\n",
                   args[i]);
      return 2;
    }
  }
  try {
    const nec::tat::TatTrainConfig& config = train_config();
    std::fprintf(stderr, "bench_tat: %s, batch %lld x %lld frames\n", config.model.to_string().c_str(),
                 static_cast<long long>(config.batch_size), static_cast<long long>(config.data.window_frames));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_tat: %s\n", e.what());
    return 1;
  }
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

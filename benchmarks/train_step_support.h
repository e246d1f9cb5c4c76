// What the training-step benchmarks (bench_tat, bench_gpt, bench_evaluator,
// bench_diffusion) share: the record their Python peers are compared on
// (parameters, the first losses, the peak memory of a step) and its counters,
// and where a step's time goes, op by op (--profile_ops=DIR).
//
//   torch::manual_seed(0);  ... make the batch, the model, the optimizer at one thread ...
//   const StepRecord record = record_first_steps(model->parameters(), [&] { return step(); });
//   for (auto _ : state) step();
//   set_step_counters(state, record);
//   profile_ops_if_asked("BM_TatTrainStep/joints:22/threads:1", [&] { step(); }, 1);
//
// The op profile: ATen's RecordFunction callbacks time every operator and
// autograd node run in a region (the records PyTorch's profiler reads, so the
// peers' profiles, benchmarks/peer_step.py, count the same things).
// Per name: calls, self time (without the records nested in it) and total
// time. top_level_ms sums the records not nested in another: the time inside
// ATen and autograd; wall_ms minus it is the time the caller spends outside
// them (C++ or Python glue, tensor creation outside ops, the allocator).
// Records of intra-op threads are not made by ATen, so a region's op times
// are the calling thread's.
#pragma once

#include <ATen/core/Tensor.h>
#include <benchmark/benchmark.h>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace nec::bench {

constexpr int64_t kWarmupSteps = 2;  // untimed steps whose losses the peer must reproduce

struct PeakRss {
  double above_start_mib = -1;  // peak RSS during the region minus RSS at its start
  double peak_mib = -1;         // peak RSS during the region
};
// Runs `region` with the kernel's peak-RSS mark reset at its start (Linux:
// /proc/self/clear_refs resets VmHWM). Free heap goes back to the system
// first, so memory the region reuses from earlier steps counts again.
PeakRss measure_peak_rss(const std::function<void()>& region);

struct StepRecord {
  int64_t parameters = 0;            // of the model
  std::vector<double> first_losses;  // of the first kWarmupSteps steps
  PeakRss memory;                    // of step kWarmupSteps + 1
};
// Takes kWarmupSteps + 1 steps (`step` returns the loss before it), the
// last under measure_peak_rss.
StepRecord record_first_steps(const std::vector<at::Tensor>& parameters, const std::function<double()>& step);
// Counters parameters, loss_step0, loss_step1, step_peak_MiB, rss_peak_MiB.
void set_step_counters(benchmark::State& state, const StepRecord& record);

// Statistics the benchmarks add to mean, median, stddev and cv.
double smallest(const std::vector<double>& values);
double largest(const std::vector<double>& values);

struct OpTime {
  int64_t calls = 0;
  double self_ms = 0;
  double total_ms = 0;
};

struct OpProfile {
  int64_t repeats = 0;      // times the region ran; every figure is a sum over them
  double wall_ms = 0;       // wall clock of the region
  double top_level_ms = 0;  // time of the records not nested in another
  std::map<std::string, OpTime> ops;
};

OpProfile profile_ops(const std::function<void()>& region, int64_t repeats);

// JSON: {"repeats", "wall_ms", "top_level_ms", "ops": {name: {"calls", "self_ms", "total_ms"}}}.
void write_op_profile(const OpProfile& profile, const std::string& path);

// The configs the step benchmarks build their models from: the repository's
// configs/ unless --configs=DIR.
const std::string& configs_dir();
// The flags of the step benchmark programs beside Google Benchmark's:
// --configs=DIR and --profile_ops=DIR. True (and DIR kept) when `arg` is one.
bool take_step_flag(const char* arg);
// With --profile_ops=DIR, the first time a label comes: `region` `repeats`
// more times under the profiler, written to DIR/<label>.json ('/' and ':' in
// the label become '_'). Else nothing.
void profile_ops_if_asked(const std::string& label, const std::function<void()>& region, int64_t repeats);

}  // namespace nec::bench

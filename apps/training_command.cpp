// The run options and the data-parallel wiring of the `nec train KIND` commands.
#include "training_command.h"

#include "torch_runtime.h"

#include "nec/train/checkpoint_io.h"
#include "nec/train/launch.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace nec::app {

void declare_training_options(CommandLine& cli) {
  cli.flag("--resume", "continue the run whose checkpoint is in --out (same config; steps may change)");
  cli.flag("--force", "replace the checkpoint in --out with a new run");
  cli.option("--threads", "N", "0", "torch threads per process; 0 = the machine's cores divided among its processes");
  cli.option("--device", "DEVICE", "cpu", "cpu, cuda or cuda:N");
  cli.option("--nproc", "N", "1", "data-parallel: run N worker processes on this machine (each takes 1/N of a batch)");
  cli.option("--dist-timeout", "SECONDS", "600",
             "data-parallel: how long a rank waits for the others before it stops with an error");
}

void apply_steps_option(const CommandLine& cli, int64_t& steps) {
  if (cli.integer("--steps") < 0) throw UsageError("--steps must be >= 0");
  if (cli.integer("--steps") > 0) steps = cli.integer("--steps");
}

void check_caption_inputs(const text::TextEncoderConfig& text, const std::string& pieces_path,
                          const std::string& config_path) {
  validate_config(text, config_path);
  if (text.backbone == text::kPiecesBackbone && pieces_path.empty()) {
    throw UsageError("--pieces SPM is required: the config's model.text.backbone is \"pieces\" (or set it to \"" +
                     std::string(text::kUseLiteBackbone) + "\")");
  }
  // A piece model the config would not read is refused rather than ignored.
  if (text.backbone != text::kPiecesBackbone && !pieces_path.empty()) {
    throw UsageError("--pieces is read only by the \"" + std::string(text::kPiecesBackbone) +
                     "\" text backbone; the config's model.text.backbone is \"" + text.backbone + "\" (leave --pieces out)");
  }
}

std::optional<int> run_workers_if_asked(const CommandLine& cli, const std::string& kind, int argc, char** argv) {
  const int nproc = cli.integer("--nproc");
  if (nproc < 1) throw UsageError("--nproc must be >= 1");
  if (cli.integer("--dist-timeout") < 1) throw UsageError("--dist-timeout must be >= 1");
  if (nproc == 1 || std::getenv("WORLD_SIZE") != nullptr) return std::nullopt;
  std::vector<std::string> args{"nec", "train", kind};
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--nproc") {
      ++i;  // its value
      continue;
    }
    if (arg.rfind("--nproc=", 0) == 0) continue;
    args.push_back(arg);
  }
  return train::run_local_workers("/proc/self/exe", args, nproc, stderr);
}

TrainingRun start_training_run(const CommandLine& cli, const std::string& out_dir) {
  TrainingRun run;
  run.resume = cli.is_set("--resume");
  run.force = cli.is_set("--force");
  if (run.resume && run.force) throw UsageError("--resume and --force exclude each other");
  std::optional<train::DistributedConfig> distributed;
  try {
    distributed = train::distributed_from_environment();
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("data-parallel run: ") + e.what());
  }
  // Rank 0 writes --out; every rank reads it to resume.
  if (!distributed || distributed->rank == 0 || run.resume) train::check_output_directory(out_dir, run.resume, run.force);
  run.device = device_option(cli);
  const int local_processes = distributed ? distributed->local_world_size : 1;
  torch::set_num_threads(train::threads_per_process(threads_option(cli), local_processes));
  if (distributed && distributed->world_size > 1) {
    distributed->timeout_seconds = cli.integer("--dist-timeout");
    run.ranks = train::Communicator::connect(*distributed);
  }
  return run;
}

int run_training_steps(const TrainingRun& run, const train::TrainingSchedule& schedule, int64_t start_step,
                       const std::string& out_dir, train::TrainingHooks hooks) {
  if (start_step >= schedule.total_steps) {
    if (run.is_main()) {
      fmt::print("the checkpoint in {} is at step {} and the run ends at step {}: nothing to do (raise --steps to go "
                 "on)\n",
                 out_dir, start_step, schedule.total_steps);
    }
    return 0;
  }
  std::fflush(stdout);
  const auto start = std::chrono::steady_clock::now();
  const train::InterruptSignals signals;
  hooks.interrupted = [&] { return run.ranks ? run.ranks->any(signals.received()) : signals.received(); };
  if (!run.is_main()) {
    hooks.validate = nullptr;
    hooks.checkpoint = nullptr;
  }
  train::ProgressReporter progress(run.is_main() ? stdout : nullptr, isatty(fileno(stdout)) != 0);
  const train::TrainingOutcome outcome = train::run_training(schedule, start_step, out_dir, hooks, progress);
  if ((outcome.stopped || outcome.interrupted) && run.is_main()) {
    fmt::print(stderr, "nec: {}{}\n", outcome.stopped ? "error: " : "", outcome.message);
  }
  if (outcome.exit_code() == 0 && run.is_main()) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fmt::print("trained steps {}-{} in {} ({:.3g} steps/s); checkpoint {}\n", start_step + 1, schedule.total_steps,
               train::format_duration(seconds), (schedule.total_steps - start_step) / std::max(seconds, 1e-9), out_dir);
  }
  return outcome.exit_code();
}

}  // namespace nec::app

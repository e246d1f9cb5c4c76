// What every `nec train KIND` command shares: the run options (--resume,
// --force, --threads, --device, --nproc, --dist-timeout), starting local
// workers or joining a data-parallel run from torchrun's environment, and the
// step loop wired so that rank 0 alone logs, validates and checkpoints.
#pragma once

#include "command_line.h"

#include "nec/motion/error.h"
#include "nec/text/text_encoder.h"

#include "nec/train/distributed.h"
#include "nec/train/loop.h"

#include <c10/core/Device.h>

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace nec::app {

// Declares --resume, --force, --threads, --device, --nproc and --dist-timeout.
void declare_training_options(CommandLine& cli);

// With --nproc N (N > 1) in a process that is not a worker yet: runs `nec
// train KIND` with the same arguments as N local workers (train/launch.h) and
// returns their exit code; otherwise std::nullopt (this process trains).
std::optional<int> run_workers_if_asked(const CommandLine& cli, const std::string& kind, int argc, char** argv);

// --steps N: the step training ends at instead of the config's (0 keeps `steps`); UsageError when negative.
void apply_steps_option(const CommandLine& cli, int64_t& steps);

// config.validate(), its complaint reported as an InputError naming `config_path`.
template <typename Config>
void validate_config(const Config& config, const std::string& config_path) {
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(config_path, 0, e.what());
  }
}

// Before a fresh training loads anything: checks the text config
// (InputError naming `config_path`) and that --pieces was given exactly when it
// reads pieces (UsageError).
void check_caption_inputs(const text::TextEncoderConfig& text, const std::string& pieces_path,
                          const std::string& config_path);

struct TrainingRun {
  bool resume = false;
  bool force = false;
  c10::Device device{c10::kCPU};
  std::unique_ptr<train::Communicator> ranks;  // null: one process

  bool is_main() const { return !ranks || ranks->is_main(); }
};

// Checks --out (train::check_output_directory; rank 0 decides, every rank
// learns the answer), sets torch threads (divided among the local workers when
// --threads is 0), and joins the data-parallel run when the environment names one.
TrainingRun start_training_run(const CommandLine& cli, const std::string& out_dir);

// run_training with the hooks a data-parallel run needs: progress only on
// rank 0 (the others stay silent), validation and checkpoints only on rank 0,
// interrupts (Ctrl-C, SIGTERM) agreed over all ranks. Prints the outcome's
// message and returns its exit code.
int run_training_steps(const TrainingRun& run, const train::TrainingSchedule& schedule, int64_t start_step,
                       const std::string& out_dir, train::TrainingHooks hooks);

}  // namespace nec::app

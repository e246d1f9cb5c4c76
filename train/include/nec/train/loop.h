// The step loop shared by the `nec train ...` commands (torch-free): a
// schedule (how many steps, when to log, validate and checkpoint), a progress
// reporter, a finite check on every step's loss terms that stops training
// with a message naming the step, the term and the last checkpoint, and
// resumption from a checkpoint's step. The model, its data and its files stay
// with the caller, behind three hooks.
//
//   TrainingSchedule schedule;                  // total_steps, log_every, validate_every, checkpoint_every
//   schedule.total_steps = 2000;
//   TrainingHooks hooks;
//   hooks.step = [&](int64_t step) {            // one optimizer step; steps count from 1
//     const Losses l = trainer.step(step);
//     return LossTerms{{"total", l.total}, {"lca", l.lca}};
//   };
//   hooks.validate = [&](int64_t step) { return LossTerms{{"accuracy", trainer.accuracy()}}; };  // optional
//   hooks.checkpoint = [&](int64_t step) { trainer.save(out_dir, step); };                      // optional
//   ProgressReporter progress(stdout, isatty(fileno(stdout)));
//   const int64_t start = resuming ? saved_step : 0;           // steps start + 1 ... total_steps run
//   const TrainingOutcome outcome = run_training(schedule, start, out_dir, hooks, progress);
//   if (outcome.stopped) { std::fprintf(stderr, "%s\n", outcome.message.c_str()); return outcome.exit_code(); }
//
// A checkpoint is written every checkpoint_every steps and after the last
// step (once when both fall together); validation likewise. When a step
// returns a NaN or infinite term, nothing more runs and no checkpoint is
// written: the last one on disk stays the newest good model. When the
// `interrupted` hook says so (Ctrl-C, see InterruptSignals), the step under
// way ends, a checkpoint is written and training stops: --resume goes on.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace nec::train {

// How much of their frozen encoders' outputs (sentence encodings of captions,
// OwO embeddings of rigs) a trainer keeps to reuse at later steps.
constexpr size_t kRememberedEncodingBytes = size_t{256} << 20;

// When things happen, counted in optimizer steps.
struct TrainingSchedule {
  int64_t total_steps = 1000;       // the step training ends at, e.g. 20000
  int64_t log_every = 100;          // a plain progress line every N steps off a terminal; 0: only the last step
  int64_t validate_every = 1000;    // validation every N steps and after the last; 0: never
  int64_t checkpoint_every = 1000;  // checkpoint every N steps and after the last; 0: only after the last

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
  bool logs_at(int64_t step) const;
  bool validates_at(int64_t step) const;
  bool checkpoints_at(int64_t step) const;
};

// Named values of one step or one validation, in display order,
// e.g. {{"total", 0.41}, {"lca", 0.20}, {"lca_accuracy", 0.93}}.
using LossTerms = std::vector<std::pair<std::string, double>>;

// Index of the first NaN or infinite term, if any.
std::optional<size_t> first_non_finite(const LossTerms& terms);

// "total 0.4123  lca 0.2011": 4 significant digits, scientific where needed.
std::string format_terms(const LossTerms& terms);

// A duration for an ETA: "42s", "3m07s", "2h05m"; "?" when negative or not finite.
std::string format_duration(double seconds);

// Prints progress. On a terminal: one line redrawn in place (at most every
// 0.2 s and on every log step) with step/total, steps/s, ETA and the loss
// terms. Otherwise: the same as a plain line on log steps. Permanent lines
// (validation, checkpoints) go above the redrawn line.
class ProgressReporter {
 public:
  // `out` null: prints nothing (the other ranks of a data-parallel run).
  // `clock` returns seconds from any fixed origin; empty: std::chrono::steady_clock.
  ProgressReporter(std::FILE* out, bool terminal, std::function<double()> clock = {});

  // Starts timing: `done_steps` were taken before (a resumed run), `total_steps` is the end.
  void start(int64_t done_steps, int64_t total_steps);
  // After step `step` with its terms; `log_step`: the schedule wants a line now.
  void step(int64_t step, const LossTerms& terms, bool log_step);
  // A permanent line, e.g. "validation at step 500: lca_accuracy 0.93".
  void line(const std::string& text);
  // Ends the redrawn line (a newline on a terminal when one is showing).
  void finish();

  // Steps per second over this run so far; 0 before the first step.
  double steps_per_second(int64_t step) const;
  // "step 120/2000  8.31 steps/s  ETA 3m46s  total 0.4123  lca 0.2011"
  std::string status(int64_t step, const LossTerms& terms) const;

 private:
  double now() const;

  std::FILE* out_;
  bool terminal_;
  std::function<double()> clock_;
  int64_t done_steps_ = 0;
  int64_t total_steps_ = 0;
  double start_time_ = 0.0;
  double last_draw_time_ = -1e300;
  bool line_showing_ = false;  // a redrawn line is on screen without its newline
};

// What the caller plugs in. `step` is required; the others are optional.
struct TrainingHooks {
  std::function<LossTerms(int64_t step)> step;      // one optimizer step; returns its terms
  std::function<LossTerms(int64_t step)> validate;  // validation metrics, printed as a line
  std::function<void(int64_t step)> checkpoint;     // writes a checkpoint at `step`
  std::function<bool()> interrupted;                // asked after every step: true = checkpoint and stop
};

struct TrainingOutcome {
  int64_t last_step = 0;              // the last step completed (the start step when none ran)
  int64_t last_checkpoint_step = -1;  // step of the newest checkpoint, -1 when there is none
  bool stopped = false;               // a loss term was NaN or infinite
  bool interrupted = false;           // the interrupted hook said stop (after a checkpoint)
  std::string message;                // why it stopped: "training stopped at step 7: loss term 'lca' is nan; ..."

  // 1 after a non-finite loss, 130 (as a shell reports SIGINT) when interrupted, else 0.
  int exit_code() const { return stopped ? 1 : (interrupted ? 130 : 0); }
};

// While one exists, SIGINT and SIGTERM do not end the process but set a flag
// that training polls between steps; the first signal also restores the
// default action, so a second Ctrl-C ends the process at once. The previous
// handlers come back when it goes. One at a time per process.
class InterruptSignals {
 public:
  InterruptSignals();
  ~InterruptSignals();
  InterruptSignals(const InterruptSignals&) = delete;
  InterruptSignals& operator=(const InterruptSignals&) = delete;

  bool received() const;
};

// Runs steps start_step + 1 ... schedule.total_steps (none when start_step
// >= total_steps). `start_step` is the step of the checkpoint a run resumes
// from (0 for a fresh run; that checkpoint then counts as the last one);
// `checkpoint_dir` only names it in messages. Exceptions from the hooks pass
// through. Throws std::invalid_argument for a bad schedule, a negative
// start_step or a missing step hook.
TrainingOutcome run_training(const TrainingSchedule& schedule, int64_t start_step, const std::string& checkpoint_dir,
                             const TrainingHooks& hooks, ProgressReporter& progress);

}  // namespace nec::train

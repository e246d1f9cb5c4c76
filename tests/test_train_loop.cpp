// The training step loop (apps/training_loop.h): NaN stop, checkpoint and
// validation cadence, resume start step, progress lines and ETA formatting.
#include "nec/train/loop.h"

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace nec::train {
namespace {

// Captures what a ProgressReporter prints.
class CapturedOutput {
 public:
  CapturedOutput() : file_(std::tmpfile()) {}
  ~CapturedOutput() { std::fclose(file_); }
  std::FILE* file() { return file_; }
  std::string text() {
    std::fflush(file_);
    std::rewind(file_);
    std::string out;
    char buffer[4096];
    size_t n = 0;
    while ((n = std::fread(buffer, 1, sizeof buffer, file_)) > 0) out.append(buffer, n);
    return out;
  }

 private:
  std::FILE* file_;
};

// A clock that advances one second per call to tick().
struct FakeClock {
  double seconds = 100.0;
  std::function<double()> function() {
    return [this] { return seconds; };
  }
};

struct Recorder {
  std::vector<int64_t> steps, validations, checkpoints;
  int64_t nan_at = -1;        // step whose 'lca' term is NaN
  std::string bad_term = "lca";

  TrainingHooks hooks() {
    TrainingHooks h;
    h.step = [this](int64_t step) {
      steps.push_back(step);
      const double lca = step == nan_at ? std::numeric_limits<double>::quiet_NaN() : 1.0 / step;
      return LossTerms{{"total", 2.0 / step}, {bad_term, lca}};
    };
    h.validate = [this](int64_t step) {
      validations.push_back(step);
      return LossTerms{{"accuracy", 0.5}};
    };
    h.checkpoint = [this](int64_t step) { checkpoints.push_back(step); };
    return h;
  }
};

TrainingSchedule schedule(int64_t total, int64_t log, int64_t validate, int64_t checkpoint) {
  TrainingSchedule s;
  s.total_steps = total;
  s.log_every = log;
  s.validate_every = validate;
  s.checkpoint_every = checkpoint;
  return s;
}

TEST(TrainingLoop, CheckpointAndValidationCadenceIncludeTheLastStepOnce) {
  CapturedOutput out;
  ProgressReporter progress(out.file(), false);
  Recorder recorder;
  const TrainingOutcome outcome = run_training(schedule(10, 5, 4, 3), 0, "runs/x", recorder.hooks(), progress);
  EXPECT_FALSE(outcome.stopped);
  EXPECT_EQ(outcome.exit_code(), 0);
  EXPECT_EQ(outcome.last_step, 10);
  EXPECT_EQ(outcome.last_checkpoint_step, 10);
  EXPECT_EQ(recorder.steps, (std::vector<int64_t>{1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  EXPECT_EQ(recorder.checkpoints, (std::vector<int64_t>{3, 6, 9, 10}));
  EXPECT_EQ(recorder.validations, (std::vector<int64_t>{4, 8, 10}));

  Recorder aligned;
  run_training(schedule(9, 0, 0, 3), 0, "runs/x", aligned.hooks(), progress);
  EXPECT_EQ(aligned.checkpoints, (std::vector<int64_t>{3, 6, 9}));  // 9 is both: written once
  EXPECT_TRUE(aligned.validations.empty());                          // validate_every 0: never

  Recorder only_last;
  run_training(schedule(4, 0, 0, 0), 0, "runs/x", only_last.hooks(), progress);
  EXPECT_EQ(only_last.checkpoints, (std::vector<int64_t>{4}));
}

TEST(TrainingLoop, PlainLinesOnLogStepsOffATerminal) {
  CapturedOutput out;
  FakeClock clock;
  ProgressReporter progress(out.file(), false, clock.function());
  Recorder recorder;
  TrainingHooks hooks = recorder.hooks();
  const auto step = hooks.step;
  hooks.step = [&](int64_t s) {
    clock.seconds += 0.5;  // two steps per second
    return step(s);
  };
  run_training(schedule(6, 4, 0, 0), 0, "runs/x", hooks, progress);
  const std::string text = out.text();
  EXPECT_EQ(text.find('\r'), std::string::npos) << text;
  EXPECT_NE(text.find("step 4/6  2 steps/s  ETA 1s  total 0.5  lca 0.25\n"), std::string::npos) << text;
  EXPECT_NE(text.find("step 6/6  2 steps/s  ETA 0s  total 0.3333  lca 0.1667\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("step 5/6"), std::string::npos) << text;
  EXPECT_NE(text.find("checkpoint at step 6: runs/x\n"), std::string::npos) << text;
}

TEST(TrainingLoop, TerminalRedrawsOneLine) {
  CapturedOutput out;
  FakeClock clock;
  ProgressReporter progress(out.file(), true, clock.function());
  Recorder recorder;
  TrainingHooks hooks = recorder.hooks();
  const auto step = hooks.step;
  hooks.step = [&](int64_t s) {
    clock.seconds += 1.0;
    return step(s);
  };
  run_training(schedule(3, 100, 0, 0), 0, "runs/x", hooks, progress);
  const std::string text = out.text();
  EXPECT_NE(text.find("\rstep 1/3  1 steps/s  ETA 2s  total 2  lca 1\x1b[K"), std::string::npos) << text;
  EXPECT_NE(text.find("\rstep 3/3"), std::string::npos) << text;
  // The checkpoint line clears the progress line and ends with a newline; nothing is left open.
  EXPECT_NE(text.find("\r\x1b[Kcheckpoint at step 3: runs/x\n"), std::string::npos) << text;
  EXPECT_EQ(text.back(), '\n');
}

TEST(TrainingLoop, NonFiniteTermStopsWithTheStepTermAndLastCheckpoint) {
  CapturedOutput out;
  ProgressReporter progress(out.file(), false);
  Recorder recorder;
  recorder.nan_at = 7;
  const TrainingOutcome outcome = run_training(schedule(20, 0, 0, 5), 0, "runs/owo", recorder.hooks(), progress);
  EXPECT_TRUE(outcome.stopped);
  EXPECT_EQ(outcome.exit_code(), 1);
  EXPECT_EQ(outcome.last_step, 6);
  EXPECT_EQ(outcome.last_checkpoint_step, 5);
  EXPECT_EQ(recorder.steps.back(), 7);
  EXPECT_EQ(recorder.checkpoints, (std::vector<int64_t>{5}));  // nothing after the bad step
  EXPECT_EQ(outcome.message,
            "training stopped at step 7: loss term 'lca' is nan; last checkpoint: runs/owo (step 5); "
            "try a lower learning rate");

  Recorder early;
  early.nan_at = 2;
  early.bad_term = "offset";
  const TrainingOutcome first = run_training(schedule(20, 0, 0, 5), 0, "runs/owo", early.hooks(), progress);
  EXPECT_EQ(first.message,
            "training stopped at step 2: loss term 'offset' is nan; last checkpoint: none; try a lower learning rate");

  TrainingHooks infinite;
  infinite.step = [](int64_t) { return LossTerms{{"total", 1.0}, {"grad_norm", -HUGE_VAL}}; };
  const TrainingOutcome negative = run_training(schedule(3, 0, 0, 0), 0, "runs/owo", infinite, progress);
  EXPECT_NE(negative.message.find("loss term 'grad_norm' is -inf"), std::string::npos) << negative.message;
}

TEST(TrainingLoop, ResumeStartsAfterTheCheckpointStep) {
  CapturedOutput out;
  ProgressReporter progress(out.file(), false);
  Recorder recorder;
  recorder.nan_at = 43;
  const TrainingOutcome outcome = run_training(schedule(50, 0, 0, 20), 40, "runs/owo", recorder.hooks(), progress);
  EXPECT_EQ(recorder.steps.front(), 41);
  EXPECT_TRUE(recorder.checkpoints.empty());
  // The checkpoint resumed from is the last good one.
  EXPECT_NE(outcome.message.find("last checkpoint: runs/owo (step 40)"), std::string::npos) << outcome.message;

  Recorder done;
  const TrainingOutcome nothing = run_training(schedule(50, 0, 0, 20), 50, "runs/owo", done.hooks(), progress);
  EXPECT_TRUE(done.steps.empty());
  EXPECT_TRUE(done.checkpoints.empty());
  EXPECT_FALSE(nothing.stopped);
  EXPECT_EQ(nothing.last_step, 50);
  EXPECT_EQ(nothing.last_checkpoint_step, 50);

  Recorder resumed;
  run_training(schedule(50, 0, 0, 20), 30, "runs/owo", resumed.hooks(), progress);
  EXPECT_EQ(resumed.steps.size(), 20u);
  EXPECT_EQ(resumed.checkpoints, (std::vector<int64_t>{40, 50}));
}

TEST(TrainingLoop, InterruptionCheckpointsTheStepAndStops) {
  CapturedOutput out;
  ProgressReporter progress(out.file(), false);
  Recorder recorder;
  TrainingHooks hooks = recorder.hooks();
  hooks.interrupted = [&] { return recorder.steps.back() >= 7; };
  const TrainingOutcome outcome = run_training(schedule(20, 0, 0, 5), 0, "runs/tat", hooks, progress);
  EXPECT_TRUE(outcome.interrupted);
  EXPECT_FALSE(outcome.stopped);
  EXPECT_EQ(outcome.exit_code(), 130);
  EXPECT_EQ(outcome.last_step, 7);
  EXPECT_EQ(outcome.last_checkpoint_step, 7);
  EXPECT_EQ(recorder.steps.back(), 7);
  EXPECT_EQ(recorder.checkpoints, (std::vector<int64_t>{5, 7}));
  EXPECT_EQ(outcome.message,
            "interrupted at step 7 of 20; checkpoint written to runs/tat; run the same command with --resume to go on");

  // On a checkpoint step it is written once; on the last step the run simply ends.
  Recorder on_cadence;
  TrainingHooks cadence_hooks = on_cadence.hooks();
  cadence_hooks.interrupted = [&] { return on_cadence.steps.back() >= 5; };
  run_training(schedule(20, 0, 0, 5), 0, "runs/tat", cadence_hooks, progress);
  EXPECT_EQ(on_cadence.checkpoints, (std::vector<int64_t>{5}));
  Recorder at_end;
  TrainingHooks end_hooks = at_end.hooks();
  end_hooks.interrupted = [] { return true; };
  const TrainingOutcome finished = run_training(schedule(1, 0, 0, 0), 0, "runs/tat", end_hooks, progress);
  EXPECT_FALSE(finished.interrupted);
  EXPECT_EQ(at_end.checkpoints, (std::vector<int64_t>{1}));
}

TEST(TrainingLoop, InterruptSignalsCatchOneSignalAndRestoreTheHandlers) {
  {
    InterruptSignals signals;
    EXPECT_FALSE(signals.received());
    EXPECT_THROW(InterruptSignals second, std::logic_error);
    std::raise(SIGTERM);  // would end the test process without the handler
    EXPECT_TRUE(signals.received());
    // The signal that came now has its default action again (a second one ends
    // the process); the other is still caught.
    auto handler_of = [](int signal_number) {
      void (*handler)(int) = std::signal(signal_number, SIG_IGN);
      std::signal(signal_number, handler);
      return handler;
    };
    EXPECT_EQ(handler_of(SIGTERM), SIG_DFL);
    EXPECT_NE(handler_of(SIGINT), SIG_DFL);
  }
  InterruptSignals again;  // the flag starts clear for the next run
  EXPECT_FALSE(again.received());
}

TEST(TrainingLoop, EtaRateAndTermFormatting) {
  EXPECT_EQ(format_duration(0.0), "0s");
  EXPECT_EQ(format_duration(42.4), "42s");
  EXPECT_EQ(format_duration(59.6), "1m00s");
  EXPECT_EQ(format_duration(187.0), "3m07s");
  EXPECT_EQ(format_duration(3599.0), "59m59s");
  EXPECT_EQ(format_duration(7500.0), "2h05m");
  EXPECT_EQ(format_duration(-1.0), "?");
  EXPECT_EQ(format_duration(std::numeric_limits<double>::infinity()), "?");
  EXPECT_EQ(format_duration(std::nan("")), "?");

  EXPECT_EQ(format_terms({{"total", 0.41234}, {"lca", 1.5e-5}, {"big", 2.5e7}, {"zero", 0.0}}),
            "total 0.4123  lca 1.500e-05  big 2.500e+07  zero 0");
  EXPECT_EQ(format_terms({}), "");

  CapturedOutput out;
  FakeClock clock;
  ProgressReporter progress(out.file(), false, clock.function());
  progress.start(100, 1100);  // resumed at step 100
  EXPECT_EQ(progress.status(100, {}), "step 100/1100  0 steps/s  ETA ?");
  clock.seconds += 40.0;
  EXPECT_DOUBLE_EQ(progress.steps_per_second(300), 5.0);  // 200 steps in 40 s
  EXPECT_EQ(progress.status(300, {{"total", 1.0}}), "step 300/1100  5 steps/s  ETA 2m40s  total 1");
}

TEST(TrainingLoop, RejectsBadSchedulesAndMissingStep) {
  CapturedOutput out;
  ProgressReporter progress(out.file(), false);
  Recorder recorder;
  EXPECT_THROW(run_training(schedule(0, 1, 1, 1), 0, "x", recorder.hooks(), progress), std::invalid_argument);
  EXPECT_THROW(run_training(schedule(5, -1, 1, 1), 0, "x", recorder.hooks(), progress), std::invalid_argument);
  EXPECT_THROW(run_training(schedule(5, 1, 1, 1), -3, "x", recorder.hooks(), progress), std::invalid_argument);
  EXPECT_THROW(run_training(schedule(5, 1, 1, 1), 0, "x", TrainingHooks{}, progress), std::invalid_argument);
  try {
    schedule(5, 1, -2, 1).validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("validate_every"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace nec::train

// The training step loop: schedule, progress line, finite check, checkpoint cadence, resume.
#include "nec/train/loop.h"

#include <chrono>
#include <cmath>
#include <csignal>
#include <stdexcept>

namespace nec::train {
namespace {

constexpr double kRedrawSeconds = 0.2;  // least time between two redraws of the terminal line

volatile std::sig_atomic_t g_interrupt_received = 0;
bool g_interrupt_installed = false;
void (*g_previous_sigint)(int) = SIG_DFL;
void (*g_previous_sigterm)(int) = SIG_DFL;

extern "C" void on_interrupt(int signal_number) {
  g_interrupt_received = 1;
  std::signal(signal_number, SIG_DFL);
}

bool every(int64_t period, int64_t step) { return period > 0 && step % period == 0; }

std::string format_value(double value) {
  char text[32];
  const double magnitude = std::fabs(value);
  if (value != 0.0 && std::isfinite(value) && (magnitude < 1e-3 || magnitude >= 1e5)) {
    std::snprintf(text, sizeof text, "%.3e", value);
  } else {
    std::snprintf(text, sizeof text, "%.4g", value);
  }
  return text;
}

}  // namespace

void TrainingSchedule::validate() const {
  if (total_steps < 1) throw std::invalid_argument("total_steps must be >= 1, got " + std::to_string(total_steps));
  if (log_every < 0) throw std::invalid_argument("log_every must be >= 0, got " + std::to_string(log_every));
  if (validate_every < 0) {
    throw std::invalid_argument("validate_every must be >= 0, got " + std::to_string(validate_every));
  }
  if (checkpoint_every < 0) {
    throw std::invalid_argument("checkpoint_every must be >= 0, got " + std::to_string(checkpoint_every));
  }
}

bool TrainingSchedule::logs_at(int64_t step) const { return step == total_steps || every(log_every, step); }

bool TrainingSchedule::validates_at(int64_t step) const {
  return validate_every > 0 && (step == total_steps || every(validate_every, step));
}

bool TrainingSchedule::checkpoints_at(int64_t step) const {
  return step == total_steps || every(checkpoint_every, step);
}

std::optional<size_t> first_non_finite(const LossTerms& terms) {
  for (size_t i = 0; i < terms.size(); ++i) {
    if (!std::isfinite(terms[i].second)) return i;
  }
  return std::nullopt;
}

std::string format_terms(const LossTerms& terms) {
  std::string out;
  for (const auto& [name, value] : terms) out += (out.empty() ? "" : "  ") + name + " " + format_value(value);
  return out;
}

std::string format_duration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return "?";
  const int64_t whole = static_cast<int64_t>(std::llround(seconds));
  char text[32];
  if (whole < 60) {
    std::snprintf(text, sizeof text, "%llds", static_cast<long long>(whole));
  } else if (whole < 3600) {
    std::snprintf(text, sizeof text, "%lldm%02llds", static_cast<long long>(whole / 60),
                  static_cast<long long>(whole % 60));
  } else {
    const int64_t minutes = (whole + 30) / 60;
    std::snprintf(text, sizeof text, "%lldh%02lldm", static_cast<long long>(minutes / 60),
                  static_cast<long long>(minutes % 60));
  }
  return text;
}

ProgressReporter::ProgressReporter(std::FILE* out, bool terminal, std::function<double()> clock)
    : out_(out), terminal_(terminal), clock_(std::move(clock)) {}

double ProgressReporter::now() const {
  if (clock_) return clock_();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void ProgressReporter::start(int64_t done_steps, int64_t total_steps) {
  done_steps_ = done_steps;
  total_steps_ = total_steps;
  start_time_ = now();
  last_draw_time_ = -1e300;
}

double ProgressReporter::steps_per_second(int64_t step) const {
  const double elapsed = now() - start_time_;
  const int64_t taken = step - done_steps_;
  if (taken <= 0 || elapsed <= 0.0) return 0.0;
  return static_cast<double>(taken) / elapsed;
}

std::string ProgressReporter::status(int64_t step, const LossTerms& terms) const {
  const double rate = steps_per_second(step);
  const double eta = rate > 0.0 ? static_cast<double>(total_steps_ - step) / rate : -1.0;
  char head[96];
  std::snprintf(head, sizeof head, "step %lld/%lld  %.3g steps/s  ETA %s", static_cast<long long>(step),
                static_cast<long long>(total_steps_), rate, format_duration(eta).c_str());
  const std::string tail = format_terms(terms);
  return tail.empty() ? std::string(head) : std::string(head) + "  " + tail;
}

void ProgressReporter::step(int64_t step, const LossTerms& terms, bool log_step) {
  if (out_ == nullptr) return;
  if (!terminal_) {
    if (log_step) {
      std::fprintf(out_, "%s\n", status(step, terms).c_str());
      std::fflush(out_);
    }
    return;
  }
  const double time = now();
  if (!log_step && time - last_draw_time_ < kRedrawSeconds) return;
  last_draw_time_ = time;
  std::fprintf(out_, "\r%s\x1b[K", status(step, terms).c_str());
  std::fflush(out_);
  line_showing_ = true;
}

void ProgressReporter::line(const std::string& text) {
  if (out_ == nullptr) return;
  if (line_showing_) std::fputs("\r\x1b[K", out_);
  std::fprintf(out_, "%s\n", text.c_str());
  std::fflush(out_);
  line_showing_ = false;
  last_draw_time_ = -1e300;  // redraw the progress line at the next step
}

void ProgressReporter::finish() {
  if (out_ == nullptr) return;
  if (line_showing_) std::fputc('\n', out_);
  std::fflush(out_);
  line_showing_ = false;
}

TrainingOutcome run_training(const TrainingSchedule& schedule, int64_t start_step, const std::string& checkpoint_dir,
                             const TrainingHooks& hooks, ProgressReporter& progress) {
  schedule.validate();
  if (start_step < 0) throw std::invalid_argument("run_training: start_step must be >= 0");
  if (!hooks.step) throw std::invalid_argument("run_training: the step hook is missing");
  TrainingOutcome outcome;
  outcome.last_step = start_step;
  outcome.last_checkpoint_step = start_step > 0 ? start_step : -1;
  progress.start(start_step, schedule.total_steps);
  for (int64_t step = start_step + 1; step <= schedule.total_steps; ++step) {
    const LossTerms terms = hooks.step(step);
    if (const std::optional<size_t> bad = first_non_finite(terms)) {
      progress.finish();
      const std::string value = std::isnan(terms[*bad].second) ? "nan" : (terms[*bad].second > 0 ? "inf" : "-inf");
      const std::string last = outcome.last_checkpoint_step > 0
                                   ? checkpoint_dir + " (step " + std::to_string(outcome.last_checkpoint_step) + ")"
                                   : "none";
      outcome.stopped = true;
      outcome.message = "training stopped at step " + std::to_string(step) + ": loss term '" + terms[*bad].first +
                        "' is " + value + "; last checkpoint: " + last + "; try a lower learning rate";
      return outcome;
    }
    outcome.last_step = step;
    progress.step(step, terms, schedule.logs_at(step));
    if (hooks.validate && schedule.validates_at(step)) {
      const LossTerms metrics = hooks.validate(step);
      progress.line("validation at step " + std::to_string(step) + ": " + format_terms(metrics));
    }
    const bool interrupted = hooks.interrupted && hooks.interrupted();
    if (hooks.checkpoint && (schedule.checkpoints_at(step) || interrupted)) {
      hooks.checkpoint(step);
      outcome.last_checkpoint_step = step;
      progress.line("checkpoint at step " + std::to_string(step) + ": " + checkpoint_dir);
    }
    if (interrupted && step < schedule.total_steps) {
      progress.finish();
      outcome.interrupted = true;
      outcome.message = "interrupted at step " + std::to_string(step) + " of " + std::to_string(schedule.total_steps) +
                        (hooks.checkpoint ? "; checkpoint written to " + checkpoint_dir +
                                                "; run the same command with --resume to go on"
                                          : "");
      return outcome;
    }
  }
  progress.finish();
  return outcome;
}

InterruptSignals::InterruptSignals() {
  if (g_interrupt_installed) throw std::logic_error("InterruptSignals: one is installed already");
  g_interrupt_installed = true;
  g_interrupt_received = 0;
  g_previous_sigint = std::signal(SIGINT, on_interrupt);
  g_previous_sigterm = std::signal(SIGTERM, on_interrupt);
}

InterruptSignals::~InterruptSignals() {
  std::signal(SIGINT, g_previous_sigint);
  std::signal(SIGTERM, g_previous_sigterm);
  g_interrupt_installed = false;
}

bool InterruptSignals::received() const { return g_interrupt_received != 0; }

}  // namespace nec::train

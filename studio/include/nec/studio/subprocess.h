// Runs a command (no shell) as a child process in a folder, its output going to a log file, with a time limit
// and a cancel flag; or hands it to a long-lived `nec worker` that keeps its models loaded between commands.
//
//   const CommandOutcome done = run_command({"nec", "info", "walk.bvh"}, folder, folder / "log.txt", 60.0);
//   if (done.exit_code != 0) report(done.error_line);
//   WorkerProcess worker("/usr/bin/nec");
//   worker.run({"/usr/bin/nec", "generate", ...}, folder, folder / "log.txt", 300.0);  // the same, warm
#pragma once

#include <sys/types.h>

#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

namespace nec::studio {

struct CommandOutcome {
  int exit_code = -1;       // the command's exit status; -1 when it could not start or was stopped by a signal
  bool timed_out = false;   // stopped after the time limit
  bool cancelled = false;   // stopped because *cancel became true
  std::string error_line;   // the log's last line holding "error:", else its last line
};

// Starts argv[0] (a path, not searched on PATH) in `folder` with stdout and stderr appended to `log` and waits:
// after `timeout_seconds` or once `cancel` (may be null) is set it is stopped (SIGTERM, then SIGKILL after 2 s).
CommandOutcome run_command(const std::vector<std::string>& argv, const std::filesystem::path& folder,
                           const std::filesystem::path& log, double timeout_seconds,
                           const std::atomic<bool>* cancel = nullptr);

// One `nec worker` child (apps/cmd_worker.cpp): started on first use, and again after it died (a crash, kill -9)
// or was stopped (the time limit, a cancel), so that one bad job costs that job only. Not thread-safe: one per
// thread that runs jobs.
class WorkerProcess {
 public:
  // `extra`: more arguments of `nec worker` (e.g. {"--models", "2"}).
  explicit WorkerProcess(std::string nec_binary, std::vector<std::string> extra = {});
  ~WorkerProcess();  // closes the worker's input (it ends), killing it when it does not within 2 s
  WorkerProcess(const WorkerProcess&) = delete;
  WorkerProcess& operator=(const WorkerProcess&) = delete;

  // As run_command; argv[0] must be the worker's nec binary (another program runs as its own process).
  CommandOutcome run(const std::vector<std::string>& argv, const std::filesystem::path& folder,
                     const std::filesystem::path& log, double timeout_seconds, const std::atomic<bool>* cancel = nullptr);
  // Starts the worker unless one runs (run() does too); "" or why it could not. Its own messages outside the
  // commands go nowhere: a command's, a crash's included, go to that command's log.
  std::string start();
  pid_t pid() const { return pid_; }  // 0 while none runs

 private:
  void stop();  // SIGTERM, SIGKILL after a grace time; reaped
  void forget();  // the worker is gone (reaped): its channel closed, none runs

  std::string nec_;
  std::vector<std::string> extra_;
  pid_t pid_ = 0;
  int channel_ = -1;  // our end of the socket pair that is the worker's stdin and stdout
};

// The last non-empty line of a text file ("" when none), reading at most its last `window` bytes.
std::string last_line(const std::filesystem::path& file, size_t window = 4096);

}  // namespace nec::studio

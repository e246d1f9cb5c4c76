// Runs a command (no shell) as a child process in a folder, its output going to a log file, with a time limit
// and a cancel flag.
//
//   const CommandOutcome done = run_command({"nec", "info", "walk.bvh"}, folder, folder / "log.txt", 60.0);
//   if (done.exit_code != 0) report(done.error_line);
#pragma once

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

// The last non-empty line of a text file ("" when none), reading at most its last `window` bytes.
std::string last_line(const std::filesystem::path& file, size_t window = 4096);

}  // namespace nec::studio

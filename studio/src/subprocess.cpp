// Child processes for the studio's jobs: posix_spawn with the output redirected to a log, polled with waitpid.
#include "nec/studio/subprocess.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>

extern char** environ;

namespace nec::studio {
namespace {

constexpr auto kPoll = std::chrono::milliseconds(20);
constexpr auto kGrace = std::chrono::seconds(2);

// Waits for `pid` until `deadline`; true (and the status) when it ended.
bool wait_until(pid_t pid, std::chrono::steady_clock::time_point deadline, int& status) {
  while (true) {
    const pid_t done = waitpid(pid, &status, WNOHANG);
    if (done == pid) return true;
    if (done < 0) return true;  // not our child any more: nothing to wait for
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(kPoll);
  }
}

std::string error_line_of(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line, error, last;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    last = line;
    if (line.find("error:") != std::string::npos) error = line;
  }
  return error.empty() ? last : error;
}

}  // namespace

CommandOutcome run_command(const std::vector<std::string>& argv, const std::filesystem::path& folder,
                           const std::filesystem::path& log, double timeout_seconds,
                           const std::atomic<bool>* cancel) {
  CommandOutcome outcome;
  if (argv.empty()) {
    outcome.error_line = "no command";
    return outcome;
  }
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addchdir_np(&actions, folder.c_str());
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    outcome.error_line = argv[0] + ": cannot start: " + std::strerror(spawned);
    return outcome;
  }

  const auto limit = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<long long>(timeout_seconds * 1000.0));
  int status = 0;
  bool ended = false;
  while (!ended) {
    const auto next = std::min(limit, std::chrono::steady_clock::now() + std::chrono::milliseconds(200));
    ended = wait_until(pid, next, status);
    if (ended) break;
    outcome.cancelled = cancel != nullptr && cancel->load();
    outcome.timed_out = std::chrono::steady_clock::now() >= limit;
    if (outcome.cancelled || outcome.timed_out) {
      kill(pid, SIGTERM);
      if (!wait_until(pid, std::chrono::steady_clock::now() + kGrace, status)) {
        kill(pid, SIGKILL);
        waitpid(pid, &status, 0);
      }
      break;
    }
  }
  outcome.exit_code = WIFEXITED(status) && !outcome.timed_out && !outcome.cancelled ? WEXITSTATUS(status) : -1;
  outcome.error_line = error_line_of(log);
  if (outcome.timed_out) outcome.error_line = "stopped after " + std::to_string(static_cast<int>(timeout_seconds)) + " s";
  if (outcome.cancelled) outcome.error_line = "cancelled";
  return outcome;
}

std::string last_line(const std::filesystem::path& file, size_t window) {
  std::ifstream in(file, std::ios::binary | std::ios::ate);
  if (!in) return "";
  const std::streamoff size = in.tellg();
  const std::streamoff start = size > static_cast<std::streamoff>(window) ? size - static_cast<std::streamoff>(window) : 0;
  in.seekg(start);
  std::string text(static_cast<size_t>(size - start), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  const size_t newline = text.find_last_of("\r\n");
  return newline == std::string::npos ? text : text.substr(newline + 1);
}

}  // namespace nec::studio

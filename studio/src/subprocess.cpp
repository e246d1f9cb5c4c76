// Child processes for the studio's jobs: posix_spawn with the output redirected to a log, polled with waitpid;
// long-lived workers spoken to over a socket pair, one JSON line each way.
#include "nec/studio/subprocess.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
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

// Stops `pid` (SIGTERM, SIGKILL after the grace time) and reaps it; its wait status.
int terminate(pid_t pid) {
  int status = 0;
  kill(pid, SIGTERM);
  if (!wait_until(pid, std::chrono::steady_clock::now() + kGrace, status)) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  return status;
}

// How a process ended, in words: "exit code 3", "killed by signal 9 (Killed)".
std::string ending(int status) {
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")";
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  return "ended";
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
  // Nothing else of the studio's: cpp-httplib's sockets are not close-on-exec, and a child holding a client's
  // connection or the listening socket would keep them open after the studio lets them go.
  posix_spawn_file_actions_addclosefrom_np(&actions, STDERR_FILENO + 1);
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
      status = terminate(pid);
      break;
    }
  }
  outcome.exit_code = WIFEXITED(status) && !outcome.timed_out && !outcome.cancelled ? WEXITSTATUS(status) : -1;
  outcome.error_line = error_line_of(log);
  if (outcome.timed_out) outcome.error_line = "stopped after " + std::to_string(static_cast<int>(timeout_seconds)) + " s";
  if (outcome.cancelled) outcome.error_line = "cancelled";
  return outcome;
}

WorkerProcess::WorkerProcess(std::string nec_binary, std::vector<std::string> extra)
    : nec_(std::move(nec_binary)), extra_(std::move(extra)) {}

WorkerProcess::~WorkerProcess() {
  if (pid_ == 0) return;
  ::close(channel_);  // end of input: the worker leaves its loop
  int status = 0;
  if (!wait_until(pid_, std::chrono::steady_clock::now() + kGrace, status)) terminate(pid_);
}

std::string WorkerProcess::start() {
  if (pid_ != 0) return "";
  int ends[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, ends) != 0) return std::string("cannot start a worker: ") + std::strerror(errno);
  std::vector<std::string> argv{nec_, "worker"};
  argv.insert(argv.end(), extra_.begin(), extra_.end());
  std::vector<char*> args;
  for (std::string& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, ends[1], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, ends[1], STDOUT_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addclosefrom_np(&actions, STDERR_FILENO + 1);  // as run_command
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(ends[1]);
  if (spawned != 0) {
    ::close(ends[0]);
    return nec_ + ": cannot start: " + std::strerror(spawned);
  }
  pid_ = pid;
  channel_ = ends[0];
  return "";
}

void WorkerProcess::stop() {
  if (pid_ == 0) return;
  const pid_t pid = pid_;
  forget();  // its input closed first: a worker between commands ends on its own
  terminate(pid);
}

void WorkerProcess::forget() {
  ::close(channel_);
  channel_ = -1;
  pid_ = 0;
}

CommandOutcome WorkerProcess::run(const std::vector<std::string>& argv, const std::filesystem::path& folder,
                                  const std::filesystem::path& log, double timeout_seconds,
                                  const std::atomic<bool>* cancel) {
  if (argv.empty() || argv[0] != nec_) return run_command(argv, folder, log, timeout_seconds, cancel);
  CommandOutcome outcome;
  int status = 0;
  if (pid_ != 0 && waitpid(pid_, &status, WNOHANG) == pid_) forget();  // died between commands: a fresh one takes this
  outcome.error_line = start();
  if (pid_ == 0) return outcome;
  nlohmann::json request = {{"args", std::vector<std::string>(argv.begin() + 1, argv.end())},
                            {"folder", std::filesystem::absolute(folder).string()},
                            {"log", std::filesystem::absolute(log).string()}};
  const std::string line = request.dump() + "\n";
  for (size_t sent = 0; sent < line.size();) {
    const ssize_t n = ::send(channel_, line.data() + sent, line.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;  // a worker gone: seen below as the end of its answers
    sent += static_cast<size_t>(n);
  }
  const auto limit = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<long long>(timeout_seconds * 1000.0));
  std::string answer;
  while (answer.empty() || answer.back() != '\n') {
    pollfd ready{channel_, POLLIN, 0};
    const int polled = ::poll(&ready, 1, 200);
    if (polled > 0) {
      char buffer[4096];
      const ssize_t n = ::recv(channel_, buffer, sizeof buffer, 0);
      if (n > 0) {
        answer.append(buffer, static_cast<size_t>(n));
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      // The worker closed its end: it died during the command (a crash, killed from outside).
      waitpid(pid_, &status, 0);
      forget();
      const std::string said = error_line_of(log);
      outcome.error_line = "nec stopped during the job (" + ending(status) + ")" + (said.empty() ? "" : ": " + said);
      return outcome;
    }
    outcome.cancelled = cancel != nullptr && cancel->load();
    outcome.timed_out = std::chrono::steady_clock::now() >= limit;
    if (outcome.cancelled || outcome.timed_out) {
      stop();  // the next command starts a fresh worker
      outcome.error_line = outcome.cancelled ? "cancelled"
                                             : "stopped after " + std::to_string(static_cast<int>(timeout_seconds)) + " s";
      return outcome;
    }
  }
  const nlohmann::json reply = nlohmann::json::parse(answer, nullptr, /*allow_exceptions=*/false);
  if (!reply.is_object() || !reply.contains("exit") || !reply["exit"].is_number_integer()) {
    stop();
    outcome.error_line = "the worker answered something else than an exit code: " + answer;
    return outcome;
  }
  outcome.exit_code = reply["exit"].get<int>();
  if (outcome.exit_code != 0) {
    outcome.error_line = reply.contains("error") && reply["error"].is_string() ? reply["error"].get<std::string>() : error_line_of(log);
  }
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

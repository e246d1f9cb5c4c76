// nec worker: a long-lived process that runs nec commands sent to it one at a time, keeping the models and
// prepared rigs it loaded (warm_cache.h), so that `nec serve` answers a request in the time the model takes.
//
// Protocol, one JSON object per line:
//   stdin  {"args": ["generate", "a dog walks", "--skeleton", "dog.bvh", "-o", "out/dog.bvh"],
//           "folder": "/abs/job", "log": "/abs/job/log.txt"}
//   stdout {"exit": 0}                                   (the command's exit code, as `nec ARGS` would give)
//          {"exit": 2, "error": "..."}                   (a request the worker could not run)
// The command runs in `folder` with its output appended to `log`; nothing else is written on stdout. A
// command that crashes takes the worker with it: the server sees the pipe close and starts another.
#include "command_line.h"
#include "commands.h"
#include "warm_cache.h"

#include "nec/motion/error.h"

#include <fcntl.h>
#include <malloc.h>
#include <unistd.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <system_error>
#include <vector>

namespace nec::app {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Writes one reply line on the protocol's descriptor.
void reply(int fd, const json& message) {
  const std::string line = message.dump() + "\n";
  for (size_t written = 0; written < line.size();) {
    const ssize_t n = ::write(fd, line.data() + written, line.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error(std::string("nec worker: cannot answer: ") + std::strerror(errno));
    written += static_cast<size_t>(n);
  }
}

// Runs one request with stdout and stderr going to its log, in its folder; the exit code.
int run_request(const json& request, int quiet_stdout, int own_stderr) {
  if (!request.is_object() || !request.contains("args") || !request["args"].is_array() || request["args"].empty()) {
    throw UsageError("a request needs \"args\": the command and its arguments");
  }
  std::vector<std::string> args{"nec"};
  for (const json& a : request["args"]) {
    if (!a.is_string()) throw UsageError("every argument must be a string");
    args.push_back(a.get<std::string>());
  }
  if (args[1] == "worker" || args[1] == "serve") throw UsageError("a worker does not run `nec " + args[1] + "`");
  const std::string folder = request.value("folder", std::string()), log = request.value("log", std::string());
  if (folder.empty() || log.empty()) throw UsageError("a request needs \"folder\" and \"log\"");
  const int log_fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (log_fd < 0) throw InputError(log, 0, std::string("cannot be written: ") + std::strerror(errno));
  const fs::path home = fs::current_path();
  std::error_code moved;
  fs::current_path(folder, moved);
  if (moved) {
    ::close(log_fd);
    throw InputError(folder, 0, "is not a folder the worker can work in: " + moved.message());
  }
  std::fflush(nullptr);
  ::dup2(log_fd, STDOUT_FILENO);
  ::dup2(log_fd, STDERR_FILENO);
  ::close(log_fd);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const int code = run_subcommand(static_cast<int>(args.size()), argv.data());
  // nec keeps freed memory in its heap (train/heap.h: no trimming, for training's speed); a worker lives on
  // after a command's peak (2.1 GB while a search embeds a database for its index): give it back.
  malloc_trim(0);
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  ::dup2(quiet_stdout, STDOUT_FILENO);
  ::dup2(own_stderr, STDERR_FILENO);
  fs::current_path(home, moved);
  return code;
}

}  // namespace

int run_worker(int argc, char** argv) {
  CommandLine cli("nec worker",
                  "Runs nec commands sent on stdin, one JSON request a line ({\"args\": [...], \"folder\", \"log\"}),\n"
                  "answering each with its exit code ({\"exit\": N}) on stdout, and keeps the models and prepared\n"
                  "rigs it loads for the next ones. `nec serve` runs its jobs in such workers.");
  cli.option("--models", "N", "4", "loaded models kept (least recently used out)");
  cli.option("--rigs", "N", "32", "prepared rigs kept (least recently used out)");
  cli.example("echo '{\"args\": [\"info\", \"walk.bvh\"], \"folder\": \"/tmp\", \"log\": \"/tmp/log.txt\"}' | nec worker");
  if (!cli.parse(argc, argv)) return 0;
  WarmCacheLimits limits;
  if (cli.integer("--models") < 1 || cli.integer("--rigs") < 1) throw UsageError("--models and --rigs must be >= 1");
  limits.models = static_cast<size_t>(cli.integer("--models"));
  limits.rigs = static_cast<size_t>(cli.integer("--rigs"));
  enable_warm_cache(limits);

  // The replies keep the real stdout; between requests stdout goes nowhere, so no stray print reaches them.
  std::fflush(nullptr);
  const int replies = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 3);
  const int own_stderr = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 3);
  const int quiet_stdout = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
  if (replies < 0 || own_stderr < 0 || quiet_stdout < 0) throw std::runtime_error("nec worker: cannot set up its output");
  ::dup2(quiet_stdout, STDOUT_FILENO);

  std::string line;
  while (std::getline(std::cin, line)) {
    if (line.empty()) continue;
    json answer;
    try {
      answer = {{"exit", run_request(json::parse(line), quiet_stdout, own_stderr)}};
    } catch (const json::exception& e) {
      answer = {{"exit", 2}, {"error", std::string("nec worker: a request is not JSON: ") + e.what()}};
    } catch (const UsageError& e) {
      answer = {{"exit", 2}, {"error", std::string("nec worker: ") + e.what()}};
    } catch (const std::exception& e) {
      answer = {{"exit", 1}, {"error", std::string("nec worker: ") + e.what()}};
    }
    reply(replies, answer);
  }
  return 0;
}

}  // namespace nec::app

// Local worker processes of one data-parallel run (fork + exec, torchrun's environment).
#include "nec/train/launch.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace nec::train {
namespace {

volatile std::sig_atomic_t g_forward_signal = 0;

extern "C" void remember_signal(int signal_number) { g_forward_signal = signal_number; }

std::string describe(int status) {
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("was killed by signal ") + strsignal(WTERMSIG(status));
  return "stopped";
}

int exit_code_of(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 1;
}

}  // namespace

int free_local_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw std::runtime_error(std::string("cannot open a socket: ") + std::strerror(errno));
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof address;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    const std::string why = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error("cannot find a free port on 127.0.0.1: " + why);
  }
  ::close(fd);
  return ntohs(address.sin_port);
}

int run_local_workers(const std::string& program, const std::vector<std::string>& args, int nproc, std::FILE* log,
                      double grace_seconds) {
  if (nproc < 1) throw std::invalid_argument("--nproc must be >= 1");
  const std::string port = std::to_string(free_local_port());
  std::vector<pid_t> workers;
  g_forward_signal = 0;
  struct sigaction forward {};
  forward.sa_handler = remember_signal;
  sigemptyset(&forward.sa_mask);
  struct sigaction previous_int {}, previous_term {};
  sigaction(SIGINT, &forward, &previous_int);
  sigaction(SIGTERM, &forward, &previous_term);

  for (int rank = 0; rank < nproc; ++rank) {
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("cannot start a worker: ") + std::strerror(errno));
    if (pid == 0) {
      // A process group of its own: a terminal's Ctrl-C reaches the launcher alone, which forwards it once.
      ::setpgid(0, 0);
      ::signal(SIGINT, SIG_DFL);
      ::signal(SIGTERM, SIG_DFL);
      const std::string rank_text = std::to_string(rank), size_text = std::to_string(nproc);
      ::setenv("RANK", rank_text.c_str(), 1);
      ::setenv("LOCAL_RANK", rank_text.c_str(), 1);
      ::setenv("WORLD_SIZE", size_text.c_str(), 1);
      ::setenv("LOCAL_WORLD_SIZE", size_text.c_str(), 1);
      ::setenv("MASTER_ADDR", "127.0.0.1", 1);
      ::setenv("MASTER_PORT", port.c_str(), 1);
      std::vector<char*> argv;
      for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
      argv.push_back(nullptr);
      ::execv(program.c_str(), argv.data());
      std::fprintf(stderr, "nec: rank %d: cannot run %s: %s\n", rank, program.c_str(), std::strerror(errno));
      std::_Exit(127);
    }
    workers.push_back(pid);
  }

  // Wait for every worker; the first failure stops the others.
  std::vector<bool> running(workers.size(), true);
  size_t left = workers.size();
  int result = 0;
  bool stopping = false;
  bool forwarded = false;  // an interrupt was passed on: workers that checkpoint and exit 130 did as asked
  auto stop_time = std::chrono::steady_clock::time_point::max();
  auto signal_all = [&](int signal_number) {
    for (size_t r = 0; r < workers.size(); ++r) {
      if (running[r]) ::kill(workers[r], signal_number);
    }
  };
  while (left > 0) {
    if (const int received = g_forward_signal; received != 0) {
      g_forward_signal = 0;
      forwarded = true;
      signal_all(received);  // every worker checkpoints and stops, as one process would
    }
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, WNOHANG);
    if (pid > 0) {
      for (size_t r = 0; r < workers.size(); ++r) {
        if (workers[r] != pid || !running[r]) continue;
        running[r] = false;
        --left;
        const int code = exit_code_of(status);
        if (forwarded && code == 130) {
          result = result == 0 ? code : result;
        } else if (code != 0 && !stopping) {
          // A rank that died is often seen after the one that failed because of it (its collective's peer
          // closed): a rank already killed by a signal is named as the cause.
          const size_t others = left;  // still running when this failure was seen
          size_t cause = r;
          int cause_status = status;
          if (WIFEXITED(status)) {
            for (size_t o = 0; o < workers.size(); ++o) {
              int other = 0;
              if (!running[o] || ::waitpid(workers[o], &other, WNOHANG) != workers[o]) continue;
              running[o] = false;
              --left;
              if (WIFSIGNALED(other)) cause = o, cause_status = other;
            }
          }
          std::fprintf(log, "nec: rank %zu %s; stopping the other %zu rank(s)\n", cause, describe(cause_status).c_str(),
                       others);
          std::fflush(log);
          result = exit_code_of(cause_status);
          stopping = true;
          signal_all(SIGTERM);
          stop_time = std::chrono::steady_clock::now() +
                      std::chrono::milliseconds(static_cast<int64_t>(grace_seconds * 1000.0));
        }
      }
      continue;
    }
    if (pid < 0 && errno != EINTR) break;
    if (stopping && std::chrono::steady_clock::now() > stop_time) {
      signal_all(SIGKILL);
      stop_time = std::chrono::steady_clock::time_point::max();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  sigaction(SIGINT, &previous_int, nullptr);
  sigaction(SIGTERM, &previous_term, nullptr);
  return result;
}

}  // namespace nec::train

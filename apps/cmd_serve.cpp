// nec serve: the local studio (studio/server.h) until Ctrl-C or SIGTERM.
#include "command_line.h"
#include "commands.h"

#include "nec/studio/server.h"

#include <fmt/format.h>

#include <csignal>
#include <filesystem>
#include <thread>

namespace nec::app {

int run_serve(int argc, char** argv) {
  CommandLine cli("nec serve",
                  "The local studio: a web page to pick or upload a rig (BVH, FBX, GLB, Collada, .x), type captions\n"
                  "on a timeline and generate, transfer a motion onto the rig, search a database by text, watch\n"
                  "the results move and download them as BVH (and GLB for a rigged asset). Jobs run nec's own\n"
                  "commands in workers that keep the models loaded (--workers at once, --queue waiting at most).\n"
                  "Every file it writes\n"
                  "lies in a work folder it removes when it stops (Ctrl-C).");
  cli.option("--port", "PORT", "8080", "port to listen on (0: any free one)");
  cli.option("--host", "HOST", "127.0.0.1", "address to listen on: 127.0.0.1 is this machine only; 0.0.0.0 exposes\n"
                                            "the studio (and its uploads and jobs) to every network the machine is on");
  cli.option("--models", "DIR", "", "a folder with gpt/, diffusion/ and evaluator/ models; default: the default models");
  cli.option("--db", "CACHE", "", "a dataset cache (`nec prepare`) to search by text; default: no search");
  cli.option("--work", "DIR", "", "where the work folder is made; default: the system's temp folder");
  cli.option("--max-upload", "MB", "32", "largest upload accepted");
  cli.option("--workers", "N", "1", "jobs run at once");
  cli.option("--queue", "N", "64", "jobs waiting at most; more are refused (HTTP 503)");
  cli.option("--threads", "N", "0", "torch threads of each job; 0 = all cores");
  cli.flag("--process-per-job", "run every command as a fresh nec process (loading its models each time) instead\n"
                                "of in workers that keep them loaded");
  cli.example("nec serve                          # then open http://127.0.0.1:8080/");
  cli.example("nec serve --port 9000 --db out/demo/cache --workers 2 --threads 1");
  if (!cli.parse(argc, argv)) return 0;

  studio::StudioOptions options;
  options.host = cli.value("--host");
  options.port = cli.integer("--port");
  if (options.port < 0 || options.port > 65535) throw UsageError("--port must be in 0..65535");
  options.models = cli.value("--models");
  options.db = cli.value("--db");
  options.work_parent = cli.value("--work");
  const int upload_mb = cli.integer("--max-upload");
  if (upload_mb < 1 || upload_mb > 1024) throw UsageError("--max-upload must be in 1..1024 MB");
  options.max_upload_bytes = static_cast<size_t>(upload_mb) << 20;
  options.workers = cli.integer("--workers");
  if (options.workers < 1 || options.workers > 64) throw UsageError("--workers must be in 1..64");
  const int queue = cli.integer("--queue");
  if (queue < 1) throw UsageError("--queue must be >= 1");
  options.queue_limit = static_cast<size_t>(queue);
  options.threads_per_job = cli.integer("--threads");
  if (options.threads_per_job < 0) throw UsageError("--threads must be >= 0");
  options.process_per_command = cli.is_set("--process-per-job");
  options.nec_binary = std::filesystem::read_symlink("/proc/self/exe").string();

  // Ctrl-C and SIGTERM are taken by this thread (sigwait) and every other thread leaves them alone.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  studio::Studio studio(options);
  const int port = studio.bind();
  fmt::print("nec studio on http://{}:{}/ (work folder {}; Ctrl-C stops it)\n", options.host, port,
             studio.work_folder().string());
  std::fflush(stdout);
  std::thread serving([&studio] { studio.serve(); });
  int received = 0;
  sigwait(&stop_signals, &received);
  studio.stop();
  serving.join();
  fmt::print("nec studio stopped; its work folder is removed\n");
  return 0;
}

}  // namespace nec::app

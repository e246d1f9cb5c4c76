// nec serve: the local studio. One page (the viewer's studio page) and a JSON API over cpp-httplib:
//   GET  /                         the page
//   GET  /api/info                 limits, models, whether a database is searchable
//   GET  /api/rigs                 the rigs to pick: one zoo creature per body plan, then the uploads
//   POST /api/rigs                 multipart "file": a BVH / FBX / GLB / Collada / .x rig (read before it is kept)
//   POST /api/generate             JSON {"rig", "captions": [{"text", "seconds"}], "seed", "model": "gpt"|"diffusion"}
//   POST /api/transfer             multipart "source" (a motion file) and "rig" (a rig id)
//   POST /api/search               JSON {"text", "k"}: the database's best clips
//   GET  /api/jobs/ID              {"state": queued|running|done|failed, "progress", "error", "files", ...}
//   GET  /api/jobs/ID/view.html    a nec view page of the job's results (the rig's mesh moving when it has one)
//   GET  /api/jobs/ID/files/NAME   one result file (BVH, GLB, caption)
// Jobs run the nec binary's own commands (generate, transfer, retrieve, convert) from a bounded queue, in
// long-lived `nec worker` processes that keep the models and rigs they loaded (one per --workers; a worker that
// crashes or passes the time limit is killed and started again). Every file the studio writes lies in its work folder, removed when it stops. Errors answer
// {"error": "..."} with 400 (bad input), 404 (no such route, rig or job), 413 (upload too large) or 503 (queue full).
//
//   Studio studio(options);          // makes the work folder and the zoo rigs; throws on a bad option
//   int port = studio.bind();        // the port it listens on (options.port 0: any free one)
//   studio.serve();                  // blocks until stop() (from another thread or a signal handler)
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>

namespace nec::studio {

struct StudioOptions {
  std::string host = "127.0.0.1";   // loopback only unless told otherwise
  int port = 8080;                   // 0: any free port
  std::string nec_binary;            // the nec executable the jobs run (required)
  std::string models;                // a folder with gpt/, diffusion/, evaluator/; "" = the default models
  std::string db;                    // a dataset cache for search; "" = no search
  std::string work_parent;           // where the work folder is made; "" = the system's temp folder
  size_t max_upload_bytes = 32u << 20;
  int workers = 1;                   // jobs run at once, each worker in a `nec worker` that keeps the models loaded
  bool process_per_command = false;  // every command a fresh nec process instead (loads its models each time)
  size_t queue_limit = 64;           // jobs waiting at most; more are refused with 503
  double job_timeout_seconds = 300;
  int threads_per_job = 0;           // torch threads of each job's command; 0 = all cores
  size_t keep_jobs = 200;            // finished jobs kept (their files) before the oldest are removed
  size_t max_uploads = 200;          // uploaded rigs kept before the oldest are removed
};

class Studio {
 public:
  explicit Studio(const StudioOptions& options);
  ~Studio();  // stops, then removes the work folder
  Studio(const Studio&) = delete;
  Studio& operator=(const Studio&) = delete;

  int bind();                              // throws std::runtime_error when the address cannot be bound
  void serve();                            // blocks until stop()
  void stop();
  const std::filesystem::path& work_folder() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace nec::studio

// The studio's job queue: each job is a list of commands run one after another in the job's own folder (their
// results under folder/out/), by a fixed number of workers; at most `capacity` jobs wait. Each worker runs the
// nec binary's commands in a long-lived `nec worker` of its own (models kept loaded between jobs; restarted
// after a crash or the time limit), other commands (or all, without a worker binary) as child processes.
//
//   JobQueue queue(/*workers=*/1, /*capacity=*/64, /*timeout_seconds=*/300, /*keep_finished=*/200, nec);
//   std::optional<std::string> id = queue.submit({"generate", folder, {{nec, "generate", ...}}});
//   if (!id) answer 503;  else queue.status(*id)->state ...
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace nec::studio {

enum class JobState { Queued, Running, Done, Failed };
const char* state_name(JobState state);

struct JobSpec {
  std::string kind;                               // what it does, e.g. "generate"
  std::filesystem::path folder;                   // made by the caller; the job's commands run here
  std::vector<std::vector<std::string>> commands;  // argv lists, run in order until one fails
};

struct JobStatus {
  std::string id, kind;
  JobState state = JobState::Queued;
  std::string progress;             // the running command's last output line
  std::string error;                // why it failed: the command's own error line
  std::vector<std::string> files;   // when done: the files under folder/out/, sorted
  std::filesystem::path folder;
  int place = 0;                    // while queued: jobs ahead of it
  double wait_seconds = 0, run_seconds = 0;
};

class JobQueue {
 public:
  // worker_binary: the nec binary whose commands run in `nec worker` processes; "" = one process per command.
  JobQueue(int workers, size_t capacity, double timeout_seconds, size_t keep_finished, std::string worker_binary = "");
  ~JobQueue();  // stops the running commands and the workers
  JobQueue(const JobQueue&) = delete;
  JobQueue& operator=(const JobQueue&) = delete;

  // The new job's id, or nullopt when `capacity` jobs are already waiting (the caller deletes spec.folder).
  std::optional<std::string> submit(JobSpec spec);
  std::optional<JobStatus> status(const std::string& id) const;
  size_t waiting() const;
  std::vector<int> worker_pids() const;  // the `nec worker` processes running now (for tests and the load check)

 private:
  struct Job;
  void work(int index);
  void forget_old_jobs();  // under lock_: the oldest finished jobs beyond keep_finished_, folders removed

  const size_t capacity_, keep_finished_;
  const double timeout_seconds_;
  const std::string worker_binary_;
  mutable std::mutex lock_;
  std::condition_variable wake_;
  std::map<std::string, std::shared_ptr<Job>> jobs_;
  std::deque<std::shared_ptr<Job>> waiting_;
  std::deque<std::string> finished_;  // ids, oldest first
  bool stopping_ = false;
  std::vector<std::thread> workers_;
  std::vector<int> worker_pids_;  // per queue worker: its nec worker's pid, 0 while none runs
  unsigned long long next_ = 0;
};

}  // namespace nec::studio

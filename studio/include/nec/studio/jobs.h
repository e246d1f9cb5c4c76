// The studio's job queue: each job is a list of commands run one after another as child processes in the job's
// own folder (their results under folder/out/), by a fixed number of workers; at most `capacity` jobs wait.
//
//   JobQueue queue(/*workers=*/1, /*capacity=*/64, /*timeout_seconds=*/300, /*keep_finished=*/200);
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
  JobQueue(int workers, size_t capacity, double timeout_seconds, size_t keep_finished);
  ~JobQueue();  // stops the running commands and the workers
  JobQueue(const JobQueue&) = delete;
  JobQueue& operator=(const JobQueue&) = delete;

  // The new job's id, or nullopt when `capacity` jobs are already waiting (the caller deletes spec.folder).
  std::optional<std::string> submit(JobSpec spec);
  std::optional<JobStatus> status(const std::string& id) const;
  size_t waiting() const;

 private:
  struct Job;
  void work();
  void forget_old_jobs();  // under lock_: the oldest finished jobs beyond keep_finished_, folders removed

  const size_t capacity_, keep_finished_;
  const double timeout_seconds_;
  mutable std::mutex lock_;
  std::condition_variable wake_;
  std::map<std::string, std::shared_ptr<Job>> jobs_;
  std::deque<std::shared_ptr<Job>> waiting_;
  std::deque<std::string> finished_;  // ids, oldest first
  bool stopping_ = false;
  std::vector<std::thread> workers_;
  unsigned long long next_ = 0;
};

}  // namespace nec::studio

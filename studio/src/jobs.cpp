// The studio's job queue: workers take jobs in submission order and run their commands as child processes.
#include "nec/studio/jobs.h"

#include "nec/studio/subprocess.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <random>
#include <system_error>

namespace nec::studio {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* state_name(JobState state) {
  switch (state) {
    case JobState::Queued: return "queued";
    case JobState::Running: return "running";
    case JobState::Done: return "done";
    case JobState::Failed: return "failed";
  }
  return "unknown";
}

struct JobQueue::Job {
  std::string id;
  JobSpec spec;
  JobState state = JobState::Queued;
  std::string error;
  std::vector<std::string> files;
  Clock::time_point submitted = Clock::now(), started{}, ended{};
  std::atomic<bool> cancel{false};
  fs::path log() const { return spec.folder / "log.txt"; }
};

JobQueue::JobQueue(int workers, size_t capacity, double timeout_seconds, size_t keep_finished, std::string worker_binary)
    : capacity_(capacity), keep_finished_(keep_finished), timeout_seconds_(timeout_seconds),
      worker_binary_(std::move(worker_binary)) {
  std::random_device seed;
  next_ = (static_cast<unsigned long long>(seed()) << 20) & 0xffffffffffull;  // ids differ between runs
  worker_pids_.assign(static_cast<size_t>(std::max(1, workers)), 0);
  for (int i = 0; i < std::max(1, workers); ++i) workers_.emplace_back([this, i] { work(i); });
}

JobQueue::~JobQueue() {
  {
    std::lock_guard<std::mutex> hold(lock_);
    stopping_ = true;
    for (auto& [id, job] : jobs_) job->cancel = true;
  }
  wake_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

std::optional<std::string> JobQueue::submit(JobSpec spec) {
  std::lock_guard<std::mutex> hold(lock_);
  if (stopping_ || waiting_.size() >= capacity_) return std::nullopt;
  auto job = std::make_shared<Job>();
  char id[24];
  std::snprintf(id, sizeof id, "j%llx", next_++);
  job->id = id;
  job->spec = std::move(spec);
  jobs_[job->id] = job;
  waiting_.push_back(job);
  wake_.notify_one();
  return job->id;
}

size_t JobQueue::waiting() const {
  std::lock_guard<std::mutex> hold(lock_);
  return waiting_.size();
}

std::vector<int> JobQueue::worker_pids() const {
  std::lock_guard<std::mutex> hold(lock_);
  std::vector<int> running;
  for (const int pid : worker_pids_) {
    if (pid != 0) running.push_back(pid);
  }
  return running;
}

std::optional<JobStatus> JobQueue::status(const std::string& id) const {
  std::lock_guard<std::mutex> hold(lock_);
  const auto found = jobs_.find(id);
  if (found == jobs_.end()) return std::nullopt;
  const Job& job = *found->second;
  JobStatus out;
  out.id = job.id;
  out.kind = job.spec.kind;
  out.state = job.state;
  out.error = job.error;
  out.files = job.files;
  out.folder = job.spec.folder;
  const auto now = Clock::now();
  const auto seconds = [](Clock::duration d) { return std::chrono::duration<double>(d).count(); };
  out.wait_seconds = seconds((job.state == JobState::Queued ? now : job.started) - job.submitted);
  if (job.state != JobState::Queued) out.run_seconds = seconds((job.state == JobState::Running ? now : job.ended) - job.started);
  if (job.state == JobState::Queued) {
    out.place = static_cast<int>(std::find(waiting_.begin(), waiting_.end(), found->second) - waiting_.begin());
  }
  if (job.state == JobState::Running) out.progress = last_line(job.log());
  return out;
}

void JobQueue::work(int index) {
  std::unique_ptr<WorkerProcess> worker;
  if (!worker_binary_.empty()) worker = std::make_unique<WorkerProcess>(worker_binary_);
  // Started ahead of the jobs, and again right after one died, so that a job finds a process running.
  const auto keep_worker = [&] {
    if (!worker) return;
    {
      std::lock_guard<std::mutex> hold(lock_);
      if (stopping_) return;  // the queue is going: no new process to stop again at once
    }
    worker->start();
    std::lock_guard<std::mutex> hold(lock_);
    worker_pids_[static_cast<size_t>(index)] = worker->pid();
  };
  keep_worker();
  while (true) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock<std::mutex> hold(lock_);
      wake_.wait(hold, [this] { return stopping_ || !waiting_.empty(); });
      if (stopping_) return;
      job = waiting_.front();
      waiting_.pop_front();
      job->state = JobState::Running;
      job->started = Clock::now();
    }
    std::string error;
    std::error_code ignored;
    fs::create_directories(job->spec.folder / "out", ignored);
    for (const std::vector<std::string>& argv : job->spec.commands) {
      const CommandOutcome done = worker ? worker->run(argv, job->spec.folder, job->log(), timeout_seconds_, &job->cancel)
                                         : run_command(argv, job->spec.folder, job->log(), timeout_seconds_, &job->cancel);
      if (done.exit_code != 0) {
        error = done.error_line.empty() ? "failed with no output" : done.error_line;
        break;
      }
    }
    keep_worker();
    std::vector<std::string> files;
    if (error.empty()) {
      for (const auto& entry : fs::directory_iterator(job->spec.folder / "out", ignored)) {
        if (entry.is_regular_file()) files.push_back(entry.path().filename().string());
      }
      std::sort(files.begin(), files.end());
    }
    std::lock_guard<std::mutex> hold(lock_);
    job->state = error.empty() ? JobState::Done : JobState::Failed;
    job->error = error;
    job->files = std::move(files);
    job->ended = Clock::now();
    finished_.push_back(job->id);
    forget_old_jobs();
  }
}

void JobQueue::forget_old_jobs() {
  while (finished_.size() > keep_finished_) {
    const auto found = jobs_.find(finished_.front());
    finished_.pop_front();
    if (found == jobs_.end()) continue;
    std::error_code ignored;
    fs::remove_all(found->second->spec.folder, ignored);
    jobs_.erase(found);
  }
}

}  // namespace nec::studio

// nec worker and the studio's use of it: a command run in a worker writes what the one-shot binary writes; the
// worker keeps the model it loaded (it still generates after the model's file is damaged in place, and loads it
// again once the file's time changes) but not the memory of a command's peak; one worker process serves job after job; a worker killed mid-job (kill -9)
// or stopped at the time limit fails that job with a clear message and the next job runs in a fresh one; one that
// died between jobs is replaced before the next.
#include "nec/motion/files.h"
#include "nec/studio/jobs.h"
#include "nec/studio/subprocess.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <signal.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace nec {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

const std::string kNec = std::string(NEC_BINARY_DIR) + "/apps/nec";
const std::string kModels = std::string(NEC_SOURCE_DIR) + "/models/default";

std::vector<std::string> generate_args(const std::string& model, const std::string& out, int seed) {
  return {kNec, "generate", "a person walks forward", "--skeleton", std::string(NEC_CMU_BVH_DIR) + "/01_01.bvh",
          "--seconds", "2", "--seed", std::to_string(seed), "--model", model, "-o", out, "--threads", "1"};
}

// A nec command slow enough to be caught running: writing many zoo creatures.
std::vector<std::string> slow_args(const std::string& out) {
  return {kNec, "zoo", "--out", out, "--creatures", "400", "--clips-per-creature", "12", "--quiet"};
}

studio::JobStatus wait_for(const studio::JobQueue& queue, const std::string& id, double seconds = 120) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(seconds * 1000));
  studio::JobStatus status = *queue.status(id);
  while (std::chrono::steady_clock::now() < until &&
         (status.state == studio::JobState::Queued || status.state == studio::JobState::Running)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    status = *queue.status(id);
  }
  return status;
}

fs::path job_folder(const TempDir& dir, const std::string& name) {
  const fs::path folder = fs::path(dir.path()) / name;
  fs::create_directories(folder / "out");
  return folder;
}

// The model's tensors damaged in place, its size and time kept: only a process that loads it again sees it.
void damage_in_place(const std::string& model) {
  const fs::path tensors = fs::path(model) / "tensors.pt";
  const auto time = fs::last_write_time(tensors);
  write_file_atomic(tensors.string(), std::string(fs::file_size(tensors), 'x'));
  fs::last_write_time(tensors, time);
}

TEST(Worker, RunsCommandsAsTheBinaryDoesAndKeepsTheModelItLoaded) {
  if (!fs::exists(kModels + "/gpt/config.json")) GTEST_SKIP() << "no default models in " << kModels;
  TempDir dir;
  const std::string model = dir / "gpt";
  fs::copy(kModels + "/gpt", model, fs::copy_options::recursive);
  studio::WorkerProcess worker(kNec);
  const fs::path folder = job_folder(dir, "job");
  const auto run = [&](const std::vector<std::string>& argv) { return worker.run(argv, folder, folder / "log.txt", 120); };

  // The same bytes as the one-shot command, and the same process for the next command.
  ASSERT_EQ(run(generate_args(model, "warm.bvh", 3)).exit_code, 0) << read_file((folder / "log.txt").string());
  const pid_t pid = worker.pid();
  ASSERT_GT(pid, 0);
  const testing::CommandResult once = testing::run_nec(
      "generate 'a person walks forward' --skeleton " + std::string(NEC_CMU_BVH_DIR) + "/01_01.bvh --seconds 2 --seed 3 --model " +
      model + " -o " + (folder / "once.bvh").string() + " --threads 1");
  ASSERT_EQ(once.exit_code, 0) << once.output;
  EXPECT_EQ(read_file((folder / "warm.bvh").string()), read_file((folder / "once.bvh").string()));

  // The model's tensors damaged in place (same size, same time): the worker still has the model it loaded ...
  const fs::path tensors = fs::path(model) / "tensors.pt";
  const auto time = fs::last_write_time(tensors);
  damage_in_place(model);
  ASSERT_EQ(run(generate_args(model, "kept.bvh", 3)).exit_code, 0) << read_file((folder / "log.txt").string());
  EXPECT_EQ(read_file((folder / "kept.bvh").string()), read_file((folder / "warm.bvh").string()));
  EXPECT_EQ(worker.pid(), pid);
  // ... which a fresh process cannot read, and neither can the worker once the file's time says it changed.
  EXPECT_NE(testing::run_nec("generate 'a person walks' --skeleton " + std::string(NEC_CMU_BVH_DIR) + "/01_01.bvh --model " +
                             model + " -o " + (folder / "fresh.bvh").string()).exit_code, 0);
  fs::last_write_time(tensors, time + std::chrono::seconds(5));
  const studio::CommandOutcome reloaded = run(generate_args(model, "reloaded.bvh", 3));
  EXPECT_EQ(reloaded.exit_code, 1);
  EXPECT_NE(reloaded.error_line.find("error:"), std::string::npos) << reloaded.error_line;
  EXPECT_FALSE(fs::exists(folder / "reloaded.bvh"));
  EXPECT_EQ(worker.pid(), pid) << "a command's error is not a crash";

  // Usage errors keep their exit code; the worker refuses to run a studio or a worker.
  EXPECT_EQ(run({kNec, "generate", "--seconds"}).exit_code, 2);
  const studio::CommandOutcome serve = run({kNec, "serve"});
  EXPECT_EQ(serve.exit_code, 2);
  EXPECT_NE(serve.error_line.find("does not run `nec serve`"), std::string::npos) << serve.error_line;
  EXPECT_EQ(worker.pid(), pid);
}

TEST(Worker, KeepsAtMostItsCapOfModelsTheLeastRecentlyUsedOut) {
  if (!fs::exists(kModels + "/gpt/config.json")) GTEST_SKIP() << "no default models in " << kModels;
  TempDir dir;
  const std::string first = dir / "first", second = dir / "second";
  fs::copy(kModels + "/gpt", first, fs::copy_options::recursive);
  fs::copy(kModels + "/gpt", second, fs::copy_options::recursive);
  studio::WorkerProcess worker(kNec, {"--models", "1"});
  const fs::path folder = job_folder(dir, "job");
  const auto generate = [&](const std::string& model, const std::string& out) {
    std::vector<std::string> argv = generate_args(model, out, 0);
    argv.push_back("--rest-from-motion");  // no stance network: the GPTs are the only models
    return worker.run(argv, folder, folder / "log.txt", 120).exit_code;
  };
  ASSERT_EQ(generate(first, "a.bvh"), 0) << read_file((folder / "log.txt").string());
  ASSERT_EQ(generate(second, "b.bvh"), 0);
  damage_in_place(second);
  EXPECT_EQ(generate(second, "b2.bvh"), 0) << "the last model used is kept";
  damage_in_place(first);
  EXPECT_EQ(generate(first, "a2.bvh"), 1) << "the first was dropped for the second and is read again";
}

// The resident memory of a process, MiB (0 when it cannot be read).
double resident_mib(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0.0;
}

TEST(Worker, GivesBackTheMemoryOfACommandsPeak) {
  if (!fs::exists(kModels + "/evaluator/config.json")) GTEST_SKIP() << "no default models in " << kModels;
  TempDir dir;
  ASSERT_EQ(testing::run_nec("zoo --out " + dir / "zoo" + " --creatures 16 --clips-per-creature 4 --seed 5 --quiet").exit_code, 0);
  ASSERT_EQ(testing::run_nec("prepare zoo=" + dir / "zoo/seen" + " -o " + dir / "db" + " --quiet").exit_code, 0);
  studio::WorkerProcess worker(kNec);
  const fs::path folder = job_folder(dir, "job");
  // The first search embeds the whole database for its index: about 2 GB at its peak on 64 clips.
  const studio::CommandOutcome searched = worker.run({kNec, "retrieve", "a person jumps", "--db", dir / "db", "-k", "3",
                                                      "--save", "out"}, folder, folder / "log.txt", 300);
  ASSERT_EQ(searched.exit_code, 0) << read_file((folder / "log.txt").string());
  const double after = resident_mib(worker.pid());
  std::printf("worker after building a 64-clip index: %.0f MiB\n", after);
  EXPECT_GT(after, 50.0);
  EXPECT_LT(after, 800.0) << "the worker kept a command's peak";
}

TEST(Worker, OneWorkerServesJobAfterJobAndAKilledOrStoppedOneIsReplaced) {
  TempDir dir;
  studio::JobQueue queue(/*workers=*/1, /*capacity=*/8, /*timeout_seconds=*/3.0, /*keep_finished=*/20, kNec);
  const auto quick = [&](const std::string& name) {
    return queue.submit({"zoo", job_folder(dir, name), {{kNec, "zoo", "--out", "out/zoo", "--creatures", "1",
                                                         "--clips-per-creature", "1", "--seconds", "1", "--quiet"}}});
  };
  const std::string first = *quick("a");
  ASSERT_EQ(wait_for(queue, first).state, studio::JobState::Done) << wait_for(queue, first).error;
  const std::vector<int> pids = queue.worker_pids();
  ASSERT_EQ(pids.size(), 1u);
  const std::string second = *quick("b");
  ASSERT_EQ(wait_for(queue, second).state, studio::JobState::Done);
  EXPECT_EQ(queue.worker_pids(), pids) << "the same worker ran both jobs";
  EXPECT_TRUE(fs::exists(fs::path(dir.path()) / "b" / "out" / "zoo")) << "the job ran in its own folder";

  // kill -9 while a job runs: that job fails in words, the next one runs in a fresh worker.
  const std::string slow = *queue.submit({"zoo", job_folder(dir, "slow"), {slow_args("out/zoo")}});
  while (queue.status(slow)->state == studio::JobState::Queued) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  ASSERT_EQ(queue.status(slow)->state, studio::JobState::Running);
  ASSERT_EQ(kill(pids[0], SIGKILL), 0);
  const studio::JobStatus killed = wait_for(queue, slow);
  EXPECT_EQ(killed.state, studio::JobState::Failed);
  EXPECT_NE(killed.error.find("nec stopped during the job (killed by signal 9"), std::string::npos) << killed.error;
  const std::string after = *quick("c");
  EXPECT_EQ(wait_for(queue, after).state, studio::JobState::Done) << wait_for(queue, after).error;
  ASSERT_EQ(queue.worker_pids().size(), 1u);
  EXPECT_NE(queue.worker_pids(), pids);

  // A worker that died between jobs (killed while idle) is replaced before the next job, which runs.
  const std::vector<int> idle = queue.worker_pids();
  ASSERT_EQ(idle.size(), 1u);
  ASSERT_EQ(kill(idle[0], SIGKILL), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const std::string after_idle = *quick("e");
  EXPECT_EQ(wait_for(queue, after_idle).state, studio::JobState::Done) << wait_for(queue, after_idle).error;
  EXPECT_NE(queue.worker_pids(), idle);

  // Past the time limit (3 s): stopped, failed with the reason, and the next job runs.
  const std::vector<int> before = queue.worker_pids();
  const std::string hung = *queue.submit({"zoo", job_folder(dir, "hung"), {slow_args("out/zoo")}});
  const studio::JobStatus stopped = wait_for(queue, hung);
  EXPECT_EQ(stopped.state, studio::JobState::Failed);
  EXPECT_EQ(stopped.error, "stopped after 3 s");
  EXPECT_LT(stopped.run_seconds, 6.0);
  const std::string next = *quick("d");
  EXPECT_EQ(wait_for(queue, next).state, studio::JobState::Done) << wait_for(queue, next).error;
  EXPECT_NE(queue.worker_pids(), before);
}

}  // namespace
}  // namespace nec

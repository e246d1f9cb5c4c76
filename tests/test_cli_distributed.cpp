// `nec train ... --nproc 2`: two processes on loopback take the steps one process takes with the same global
// batch; a run resumes with another number of processes; a worker that dies stops the run, naming its rank.
#include "test_support.h"

#include "nec/motion/files.h"
#include "nec/tat/checkpoint.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

namespace nec {
namespace {

using testing::CommandResult;
using testing::contains;
using testing::run_nec;

constexpr const char* kOwoConfig = R"({
  "encoder": {"name_dim": 0, "dim": 16, "layers": 1, "heads": 2, "edge_dim": 8},
  "pretrain": {"pairs_per_skeleton": 16},
  "data": {"held_out": [], "poses_per_skeleton": 4},
  "names": false, "batch_size": 4, "steps": 3, "log_every": 1, "validate_every": 0, "checkpoint_every": 0, "seed": 3
})";

// Equal masks (one skeleton, clips longer than the window, no augmentation) make the ranks' shares weigh exactly
// what they weigh in one process; a constant learning rate lets a resumed run be compared with a straight one.
constexpr const char* kTatConfig = R"({"model": {"kind": "nec-rvq", "dim": 16, "blocks": 2, "attention_layers": 1,
  "heads": 2, "quantizer": {"layers": 2, "codebook_size": 16, "code_dim": 16}},
  "optimizer": {"learning_rate": 0.003, "final_lr_fraction": 1.0, "warmup_steps": 0},
  "data": {"window_frames": 16, "joint_buckets": 0, "augment": {"probability": 0.0}}, "steps": 5, "batch_size": 4,
  "log_every": 1, "validate_every": 0, "checkpoint_every": 0, "seed": 1})";

class CliDistributed : public testing::SharedFolderTest {
 protected:
  static void SetUpTestSuite() {
    SharedFolderTest::SetUpTestSuite();
    const testing::TempDir& d = shared_folder();
    const CommandResult zoo = run_nec("zoo --out " + d / "zoo" + " --creatures 1 --plans quadruped "
                                      "--clips-per-creature 12 --seconds 2 --seed 4 --quiet");
    ASSERT_EQ(zoo.exit_code, 0) << zoo.output;
    const CommandResult prepare =
        run_nec("prepare zoo=" + d / "zoo/seen" + " --val 0 --test 0 -o " + d / "cache" + " --quiet");
    ASSERT_EQ(prepare.exit_code, 0) << prepare.output;
    const CommandResult owo = run_nec("train owo --config " + d.write("owo.json", kOwoConfig) + " --data " +
                                      d / "cache" + " --out " + d / "owo" + " --threads 1");
    ASSERT_EQ(owo.exit_code, 0) << owo.output;
    d.write("tat.json", kTatConfig);
  }
  static std::string train_tat(const std::string& out, const std::string& extra) {
    return "train tat --config " + shared("tat.json") + " --data " + shared("cache") + " --owo " + shared("owo") +
           " --out " + out + " --threads 1 " + extra;
  }
};

// How far apart the parameters and buffers of two tokenizer checkpoints are.
struct Difference {
  double largest = 0.0;  // max |a - b|
  double mean = 0.0;     // mean |a - b| over every element
  std::string where;     // the tensor of the largest
};

Difference difference(const std::string& a, const std::string& b) {
  const tat::LoadedTatCheckpoint first = tat::load_tat_checkpoint(a), second = tat::load_tat_checkpoint(b);
  auto tensors_of = [](const tat::LoadedTatCheckpoint& m) {
    auto named = m.tokenizer->named_parameters();
    for (const auto& item : m.tokenizer->named_buffers()) named.insert(item.key(), item.value());
    return named;
  };
  const auto x = tensors_of(first), y = tensors_of(second);
  Difference out;
  double sum = 0.0;
  int64_t count = 0;
  for (const auto& item : x) {
    const at::Tensor gap = (item.value().to(torch::kDouble) - y[item.key()].to(torch::kDouble)).abs();
    sum += gap.sum().item<double>();
    count += gap.numel();
    if (gap.max().item<double>() > out.largest) {
      out.largest = gap.max().item<double>();
      out.where = item.key();
    }
  }
  out.mean = sum / static_cast<double>(count);
  return out;
}

// The loss terms of a progress line, without the rank-local perplexities and the timing.
std::string losses(const std::string& output, const std::string& step) {
  const std::string line = testing::last_line_starting(output, step);
  const size_t begin = line.find("loss"), end = line.find("ppl0");
  return begin == std::string::npos ? "(no line " + step + ")" : line.substr(begin, end - begin);
}

// Float sums in another order differ in the last bits; Adam turns a gradient that is zero but for rounding
// (the key bias of an attention: softmax ignores it) into a step of up to the learning rate either way. So
// the parameters agree on average within float noise, and no single one by more than a tenth of what the
// learning rate lets it move in these steps; a wrong share (say both ranks on the same items) moves most
// parameters by about the learning rate each step.
constexpr double kLearningRate = 0.003;
constexpr double kMeanTolerance = 1e-6;

TEST_F(CliDistributed, TwoProcessesTakeTheStepsOfOne) {
  const CommandResult one = run_nec(train_tat(path("one"), "--steps 3"));
  ASSERT_EQ(one.exit_code, 0) << one.output;
  const CommandResult two = run_nec(train_tat(path("two"), "--steps 3 --nproc 2"));
  ASSERT_EQ(two.exit_code, 0) << two.output;
  EXPECT_TRUE(contains(two.output, "2 process(es) x 1 threads")) << two.output;
  // Rank 0 alone prints: one progress line per step.
  EXPECT_EQ(two.output.find("step 3/3"), two.output.rfind("step 3/3")) << two.output;
  EXPECT_EQ(losses(two.output, "step 3/3"), losses(one.output, "step 3/3"));
  const Difference gap = difference(path("one"), path("two"));
  std::printf("parameters, 1 process vs 2 after 3 steps: mean difference %.3g, largest %.3g (%s)\n", gap.mean,
              gap.largest, gap.where.c_str());
  EXPECT_LT(gap.mean, kMeanTolerance);
  EXPECT_LT(gap.largest, 0.1 * kLearningRate * 3) << gap.where;
}

TEST_F(CliDistributed, ARunResumesWithAnotherNumberOfProcesses) {
  const CommandResult straight = run_nec(train_tat(path("straight"), "--steps 5"));
  ASSERT_EQ(straight.exit_code, 0) << straight.output;
  const CommandResult first = run_nec(train_tat(path("split"), "--steps 3 --nproc 2"));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const CommandResult rest = run_nec(train_tat(path("split"), "--steps 5 --resume"));
  ASSERT_EQ(rest.exit_code, 0) << rest.output;
  EXPECT_EQ(losses(rest.output, "step 5/5"), losses(straight.output, "step 5/5"));
  const Difference gap = difference(path("straight"), path("split"));
  std::printf("parameters, 5 steps straight vs 3 on 2 processes + 2 resumed on 1: mean difference %.3g, largest "
              "%.3g (%s)\n",
              gap.mean, gap.largest, gap.where.c_str());
  EXPECT_LT(gap.mean, kMeanTolerance);
  EXPECT_LT(gap.largest, 0.1 * kLearningRate * 5) << gap.where;
}

TEST_F(CliDistributed, AWorkerThatDiesStopsTheRunAndIsNamed) {
  // A long run; once it is stepping, rank 1 is killed.
  const std::string log = path("log.txt");
  const std::string nec = std::string(NEC_BINARY_DIR) + "/apps/nec ";
  const std::string script =
      nec + train_tat(path("killed"), "--steps 100000 --nproc 2") + " > " + log + " 2>&1 & launcher=$!; " +
      "for i in $(seq 300); do sleep 0.1; grep -q 'step 2/' " + log + " && break; done; " +
      "for d in /proc/[0-9]*; do if grep -qs \"^PPid:[[:space:]]*$launcher$\" $d/status && "
      "tr '\\0' '\\n' < $d/environ 2>/dev/null | grep -qx RANK=1; then kill -9 ${d#/proc/}; fi; done; "
      "wait $launcher; echo \"launcher exit $?\" >> " + log;
  const std::string script_path = dir_.write("kill_rank_1.sh", script + "\n");
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(std::system(("bash " + script_path).c_str()), 0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string output = read_file(log);
  std::printf("stopped %.1f s after the start:\n%s", seconds, output.substr(output.size() > 400 ? output.size() - 400 : 0).c_str());
  EXPECT_TRUE(contains(output, "nec: rank 1 was killed by signal")) << output;
  EXPECT_TRUE(contains(output, "stopping the other 1 rank(s)")) << output;
  EXPECT_TRUE(contains(output, "launcher exit 137")) << output;
  EXPECT_LT(seconds, 60.0);
}

}  // namespace
}  // namespace nec

// `nec train` and `nec eval` as a user runs them: a tiny OwO run on a small
// zoo cache writes checkpoints, resumes where it stopped (taking the same
// steps as a run that never stopped), stops on NaN with a message, refuses bad
// configs and inputs naming the problem, and evaluates on held-out skeletons.
#include "nec/corpus/dataset.h"
#include "nec/motion/files.h"
#include "nec/text/word_vectors.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace nec {
namespace {

namespace fs = std::filesystem;

using testing::CommandResult;
using testing::last_line_starting;
using testing::contains;
using testing::run_nec;

// A tiny model that takes a step in milliseconds; one line per step. The
// learning rate is constant after warm-up, so a run to step 4 resumed to step 7
// takes the steps of a run to step 7.
std::string tiny_config(const std::string& optimizer = R"({"learning_rate": 0.003, "warmup_steps": 2, "final_lr_fraction": 1})") {
  return R"({
  "encoder": {"name_dim": 0, "dim": 16, "layers": 1, "heads": 2, "edge_dim": 8},
  "pretrain": {"pairs_per_skeleton": 16},
  "optimizer": )" + optimizer + R"(,
  "data": {"held_out": ["spider"], "poses_per_skeleton": 4},
  "names": false,
  "batch_size": 4,
  "steps": 4,
  "log_every": 1,
  "validate_every": 4,
  "checkpoint_every": 2,
  "seed": 3
})";
}

class CliTrain : public testing::SharedFolderTest {
 protected:
  // One zoo cache for every test: 9 creatures, one per plan, the spider held out.
  static void SetUpTestSuite() {
    SharedFolderTest::SetUpTestSuite();
    const testing::TempDir& d = shared_folder();
    const CommandResult zoo = run_nec("zoo --out " + d / "zoo" + " --creatures 9 --clips-per-creature 1 --seconds 1 "
                                      "--seed 2 --hold-out spider --quiet");
    ASSERT_EQ(zoo.exit_code, 0) << zoo.output;
    const CommandResult prepare = run_nec("prepare zoo=" + d / "zoo/seen" + " held=" + d / "zoo/held_out" +
                                          " --hold-out-dataset held -o " + d / "cache" + " --quiet");
    ASSERT_EQ(prepare.exit_code, 0) << prepare.output;
  }
  static std::string cache() { return shared("cache"); }
  std::string write(const std::string& name, const std::string& text) const { return dir_.write(name, text); }
  std::string train(const std::string& config, const std::string& out, const std::string& extra = "") const {
    return "train owo --config " + config + " --data " + cache() + " --out " + out + " --threads 1 " + extra;
  }
};

TEST_F(CliTrain, DispatchByModel) {
  const CommandResult overview = run_nec("train");
  EXPECT_EQ(overview.exit_code, 2);
  EXPECT_TRUE(contains(overview.output, "owo")) << overview.output;
  const CommandResult unknown = run_nec("train unicorn");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_TRUE(contains(unknown.output, "unknown model 'unicorn' (known: owo")) << unknown.output;
  const CommandResult help = run_nec("train owo --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_TRUE(contains(help.output, "--threads N") && contains(help.output, "(default: cpu)")) << help.output;
  // The config's fields, with their defaults, from the config's one field list.
  for (const char* field : {"fields of --config", "encoder.graph.position_frequencies = 4", "data.augment.probability = 0.8",
                            "optimizer.learning_rate = 0.001", "steps = 2000"}) {
    EXPECT_TRUE(contains(help.output, field)) << field << "\n" << help.output;
  }
  const CommandResult tat_help = run_nec("train tat --help");
  EXPECT_EQ(tat_help.exit_code, 0);
  for (const char* field : {"model.kind = \"nec-rvq\"", "(nec-rvq, nec-vq, zero-pad-rvq)", "data.window_frames = 64",
                            "data.augment.kinds = [\"rest\",\"length\",\"remove\",\"subdivide\"]",
                            "optimizer.learning_rate = 0.0002"}) {
    EXPECT_TRUE(contains(tat_help.output, field)) << field << "\n" << tat_help.output;
  }
  const CommandResult evaluator_help = run_nec("train evaluator --help");
  EXPECT_EQ(evaluator_help.exit_code, 0);
  for (const char* field : {"model.text.piece_dropout = 0.1", "model.motion.patch_frames = 4", "batch_size = 64",
                            "optimizer.learning_rate = 0.0003", "OUT/best"}) {
    EXPECT_TRUE(contains(evaluator_help.output, field)) << field << "\n" << evaluator_help.output;
  }
  const CommandResult no_pieces =
      run_nec("train evaluator --config " + write("e.json", "{}") + " --data " + cache() + " --out " + path("e") + " --owo x");
  EXPECT_EQ(no_pieces.exit_code, 2) << no_pieces.output;
  EXPECT_TRUE(contains(no_pieces.output, "--pieces SPM is required: the config's model.text.backbone is \"pieces\"")) << no_pieces.output;
  EXPECT_FALSE(std::filesystem::exists(path("e")));
  const CommandResult eval = run_nec("eval frob");
  EXPECT_EQ(eval.exit_code, 2);
  EXPECT_TRUE(contains(eval.output, "unknown evaluation 'frob' (known: owo")) << eval.output;
}

TEST_F(CliTrain, CheckpointsResumeAndEvaluate) {
  const std::string config = write("tiny.json", tiny_config());
  const std::string out = path("runs/owo");
  const CommandResult first = run_nec(train(config, out, "--no-names"));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_TRUE(contains(first.output, "step 4/4")) << first.output;
  EXPECT_TRUE(contains(first.output, "checkpoint at step 2: " + out)) << first.output;
  EXPECT_TRUE(contains(first.output, "checkpoint at step 4: " + out)) << first.output;
  EXPECT_TRUE(contains(first.output, "validation at step 4: held_out_lca_acc")) << first.output;
  for (const char* file : {"config.json", "tensors.pt", "training.json", "optimizer.pt"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / file)) << file;
  }
  EXPECT_TRUE(contains(read_file(out + "/config.json"), "\"training_step\": 4"));

  // Without --resume an existing checkpoint is never overwritten.
  const CommandResult again = run_nec(train(config, out, "--no-names"));
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_TRUE(contains(again.output, "already holds a checkpoint; pass --resume")) << again.output;

  // Resume to step 7: the steps continue from 5, and match a run that never stopped.
  const CommandResult resumed = run_nec(train(config, out, "--no-names --resume --steps 7"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(contains(resumed.output, "resumed  " + out + " at step 4")) << resumed.output;
  EXPECT_FALSE(contains(resumed.output, "step 4/7")) << resumed.output;
  EXPECT_TRUE(contains(resumed.output, "step 5/7")) << resumed.output;
  EXPECT_TRUE(contains(read_file(out + "/training.json"), "\"step\": 7"));
  const CommandResult straight = run_nec(train(config, path("runs/straight"), "--no-names --steps 7"));
  ASSERT_EQ(straight.exit_code, 0) << straight.output;
  auto terms_of = [](const std::string& line) { return line.substr(line.find("total")); };
  const std::string resumed_line = last_line_starting(resumed.output, "step 7/7");
  const std::string straight_line = last_line_starting(straight.output, "step 7/7");
  ASSERT_FALSE(resumed_line.empty()) << resumed.output;
  EXPECT_EQ(terms_of(resumed_line), terms_of(straight_line));

  // Resuming with another config names the field.
  const std::string changed = write("changed.json", tiny_config(R"({"learning_rate": 0.01, "warmup_steps": 2, "final_lr_fraction": 1})"));
  const CommandResult mismatch = run_nec(train(changed, out, "--no-names --resume --steps 9"));
  EXPECT_EQ(mismatch.exit_code, 1);
  EXPECT_TRUE(contains(mismatch.output, "cannot resume: the config differs in 'optimizer.learning_rate'")) << mismatch.output;

  // Held-out evaluation: a table, and JSON with every number.
  const std::string json = path("eval.json");
  const CommandResult eval = run_nec("eval owo --model " + out + " --data " + cache() + " --json " + json + " --threads 1");
  ASSERT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_TRUE(contains(eval.output, "| held out: spider | 1 |")) << eval.output;
  EXPECT_TRUE(contains(eval.output, "| training skeletons | 8 |")) << eval.output;
  EXPECT_TRUE(contains(eval.output, "trees rebuilt from the exact LCA matrix | trees rebuilt from the LCA probabilities |"))
      << eval.output;
  const std::string written = read_file(json);
  EXPECT_TRUE(contains(written, "\"rebuild_rate\"")) << written;
  EXPECT_TRUE(contains(written, "\"decode_rate\"")) << written;
  EXPECT_TRUE(contains(written, "\"decoded_wrong_parents\"")) << written;
  EXPECT_TRUE(contains(written, "\"offset_percent_of_diameter\"")) << written;
}

TEST_F(CliTrain, NonFiniteLossStopsWithTheStepAndExitOne) {
  const std::string config = write("nan.json", tiny_config(R"({"learning_rate": 1e30, "warmup_steps": 0, "grad_clip": 0})"));
  const std::string out = path("runs/nan");
  const CommandResult run = run_nec(train(config, out, "--no-names --steps 50"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_TRUE(contains(run.output, "nec: error: training stopped at step ")) << run.output;
  EXPECT_TRUE(contains(run.output, "; try a lower learning rate")) << run.output;
  EXPECT_TRUE(contains(run.output, "loss term '")) << run.output;
}

TEST_F(CliTrain, BadInputNamesTheProblemAndWritesNothing) {
  const std::string out = path("runs/bad");
  const std::string unknown = write("unknown.json", R"({"optimizer": {"lr": 0.1}})");
  CommandResult run = run_nec(train(unknown, out, "--no-names"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.output, "unknown.json: field 'optimizer.lr' is not a known field")) << run.output;

  const std::string no_plan = write("no_plan.json", tiny_config());
  run = run_nec("train owo --config " + no_plan + " --data " + path("no_cache") + " --out " + out + " --no-names");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.output, "no_cache")) << run.output;

  const std::string dragons = write("dragons.json", R"({"names": false, "encoder": {"name_dim": 0},
                                                       "data": {"held_out": ["dragonfly"]}})");
  run = run_nec(train(dragons, out, "--no-names"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.output, "hold-out pattern 'dragonfly' matches no skeleton")) << run.output;

  // Names asked for, vectors missing: say how to get them, or to run without.
  const std::string named = write("named.json", R"({"data": {"held_out": ["spider"]}})");
  run = run_nec(train(named, out, "--glove " + path("absent.bin")));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.output, "nec text import-glove")) << run.output;
  EXPECT_TRUE(contains(run.output, "--no-names")) << run.output;

  run = run_nec(train(no_plan, out, "--no-names --device tpu"));
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_TRUE(contains(run.output, "unknown device 'tpu' (known: cpu, cuda, cuda:N)")) << run.output;

  run = run_nec(train(no_plan, out, "--no-names --resume"));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.output, "no checkpoint to resume")) << run.output;
  EXPECT_FALSE(fs::exists(out));

  run = run_nec("eval owo --model " + path("runs/none") + " --data " + cache());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_TRUE(contains(run.output, "runs/none")) << run.output;
}

// `nec text subset`: a small vector file that embeds the corpus's joint names
// exactly as the full file does, without the words no joint uses.
TEST_F(CliTrain, TextTrainTokenizerReadsTheCorpusCaptionsAndNeverOverwrites) {
  const std::string model = path("spm.model");
  const CommandResult trained = run_nec("text train-tokenizer --data " + cache() + " -o " + model + " --vocab-size 200");
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  EXPECT_TRUE(contains(trained.output, "pieces (bpe) from")) << trained.output;
  EXPECT_TRUE(contains(trained.output, "of the train split")) << trained.output;
  const CommandResult again = run_nec("text train-tokenizer --data " + cache() + " -o " + model);
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_TRUE(contains(again.output, "exists; pass --force to replace it")) << again.output;
  EXPECT_EQ(run_nec("text train-tokenizer --data " + cache() + " -o " + model + " --force").exit_code, 0);

  const CommandResult pieces = run_nec("text pieces \"A Spider, 2 legs!\" --model " + model);
  ASSERT_EQ(pieces.exit_code, 0) << pieces.output;
  EXPECT_TRUE(contains(pieces.output, "normalized  a spider two legs")) << pieces.output;
  EXPECT_TRUE(contains(pieces.output, "decoded     a spider two legs")) << pieces.output;
  const CommandResult empty = run_nec("text pieces \"\" --model " + model);
  EXPECT_EQ(empty.exit_code, 1);
  EXPECT_TRUE(contains(empty.output, "CAPTION: empty")) << empty.output;
  const CommandResult no_model = run_nec("text pieces \"a dog\" --model " + path("none.model"));
  EXPECT_EQ(no_model.exit_code, 1);
  EXPECT_TRUE(contains(no_model.output, "no such piece model")) << no_model.output;
}

TEST_F(CliTrain, TextSubsetEmbedsTheCorpusNamesLikeTheFullFile) {
  const std::vector<std::string> words = {"left", "right", "leg", "upper", "head", "neck", "spine", "tail", "banana"};
  std::vector<float> rows;
  for (size_t i = 0; i < words.size() * 4; ++i) rows.push_back(static_cast<float>(i % 7) - 0.5f * static_cast<float>(i % 3));
  const std::string full_path = path("full.bin"), small_path = path("small.bin");
  text::write_word_vectors(full_path, words, rows, 4);

  const CommandResult run = run_nec("text subset " + cache() + " --glove " + full_path + " -o " + small_path);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const text::WordVectors full = text::WordVectors::load(full_path), small = text::WordVectors::load(small_path);
  EXPECT_FALSE(small.index_of("banana").has_value());
  EXPECT_TRUE(small.index_of("leg").has_value() && small.index_of("head").has_value());
  EXPECT_LT(small.size(), full.size());
  size_t names = 0;
  for (const CachedSkeleton& s : read_cache(cache()).skeletons) {
    for (const std::string& name : s.skeleton.names) {
      EXPECT_EQ(full.embed_joint_name(name), small.embed_joint_name(name)) << name;
      ++names;
    }
  }
  EXPECT_GT(names, 50u);

  const CommandResult no_out = run_nec("text subset " + cache() + " --glove " + full_path);
  EXPECT_EQ(no_out.exit_code, 2);
  EXPECT_TRUE(contains(no_out.output, "-o")) << no_out.output;
}

}  // namespace
}  // namespace nec

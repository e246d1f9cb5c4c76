// The evaluator's commands end to end on a small zoo cache: nec train
// evaluator (and its best checkpoint), nec eval retrieval, nec retrieve with
// its stored index, nec eval t2m, and the errors a user sees.
#include "nec/motion/bvh.h"
#include "nec/corpus/dataset.h"
#include "nec/motion/files.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace nec {
namespace {

namespace fs = std::filesystem;

using testing::CommandResult;
using testing::contains;
using testing::run_nec;

class CliEvaluator : public testing::SharedFolderTest {
 protected:
  // A zoo cache (9 creatures x 12 clips, the spider held out), its piece model,
  // a tiny OwO encoder and a tiny evaluator trained on them.
  static void SetUpTestSuite() {
    SharedFolderTest::SetUpTestSuite();
    const testing::TempDir& d = shared_folder();
    testing::make_captioned_zoo(d, 12, 4);
    if (HasFatalFailure()) return;
    write_file_atomic(d / "eval.json", R"({
      "model": {"motion": {"dim": 16, "heads": 2, "feedforward": 32, "temporal_layers": 1, "max_steps": 16, "output_dim": 16},
                "text": {"word_dim": 0, "dim": 16, "heads": 2, "feedforward": 32, "layers": 1, "max_pieces": 128, "output_dim": 16}},
      "data": {"window_frames": 32},
      "batch_size": 8, "steps": 6, "log_every": 2, "validate_every": 3, "checkpoint_every": 3, "seed": 1})");
  }

  static std::string cache() { return shared_folder() / "cache"; }
  static std::string train_evaluator(const std::string& out, const std::string& extra = "") {
    const testing::TempDir& d = shared_folder();
    return "train evaluator --config " + d / "eval.json" + " --data " + cache() + " --owo " + d / "owo" + " --pieces " +
           d / "spm.model" + " --out " + out + " --threads 1 " + extra;
  }
};

TEST_F(CliEvaluator, TrainsKeepsTheBestAndResumes) {
  const std::string out = path("runs/eval");
  const CommandResult first = run_nec(train_evaluator(out));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_TRUE(contains(first.output, "validation at step 3: val_r1")) << first.output;
  EXPECT_TRUE(contains(first.output, "best: " + out + "/best (val R@3")) << first.output;
  EXPECT_TRUE(fs::exists(fs::path(out) / "best" / "config.json"));
  EXPECT_TRUE(fs::exists(fs::path(out) / "pieces.model"));
  const CommandResult resumed = run_nec(train_evaluator(out, "--resume --steps 8"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(contains(resumed.output, "steps 7-8 of")) << resumed.output;
  EXPECT_TRUE(fs::exists(fs::path(out) / "best" / "config.json"));
  // A run into a finished checkpoint without --resume or --force is refused, touching nothing.
  const CommandResult again = run_nec(train_evaluator(out));
  EXPECT_EQ(again.exit_code, 1) << again.output;
}

TEST_F(CliEvaluator, TrainsOnTheSentenceEncoderWithoutAPieceModel) {
  const testing::TempDir& d = shared_folder();
  write_file_atomic(d / "eval_use.json", R"({
    "model": {"motion": {"dim": 16, "heads": 2, "feedforward": 32, "temporal_layers": 1, "max_steps": 16, "output_dim": 16},
              "text": {"backbone": "use-lite", "word_dim": 0, "dim": 16, "layers": 0, "output_dim": 16}},
    "data": {"window_frames": 32},
    "batch_size": 8, "steps": 6, "log_every": 2, "validate_every": 3, "checkpoint_every": 3, "seed": 1})");
  const std::string out = path("runs/eval-use");
  const std::string train =
      "train evaluator --config " + d / "eval_use.json" + " --data " + cache() + " --owo " + d / "owo" + " --out " + out;
  const CommandResult first = run_nec(train + " --threads 1");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_FALSE(fs::exists(fs::path(out) / "pieces.model"));
  EXPECT_TRUE(contains(read_file(out + "/config.json"), R"("backbone": "use-lite")"));
  const CommandResult resumed = run_nec(train + " --threads 1 --resume --steps 8");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(contains(resumed.output, "steps 7-8 of")) << resumed.output;
  const CommandResult query = run_nec("retrieve \"somebody strolls along\" --db " + cache() + " --evaluator " + out + " -k 2");
  ASSERT_EQ(query.exit_code, 0) << query.output;
  EXPECT_TRUE(contains(query.output, "| 2 | ")) << query.output;
  // The pieces backbone (the default when the config does not say) still needs its piece model.
  const CommandResult no_pieces = run_nec("train evaluator --config " + d / "eval.json" + " --data " + cache() +
                                          " --owo " + d / "owo" + " --out " + path("runs/eval-no-pieces"));
  EXPECT_EQ(no_pieces.exit_code, 2) << no_pieces.output;
  EXPECT_TRUE(contains(no_pieces.output, "--pieces SPM is required")) << no_pieces.output;
  // A piece model the use-lite config would not read is refused, not ignored.
  const CommandResult unread_pieces = run_nec(train + " --pieces " + d / "spm.model" + " --force");
  EXPECT_EQ(unread_pieces.exit_code, 2) << unread_pieces.output;
  EXPECT_TRUE(contains(unread_pieces.output, "--pieces is read only by the \"pieces\" text backbone")) << unread_pieces.output;
}

TEST_F(CliEvaluator, RetrievalEvaluationAndQueries) {
  const std::string out = path("runs/eval");
  ASSERT_EQ(run_nec(train_evaluator(out)).exit_code, 0);
  const std::string best = out + "/best";

  const CommandResult table = run_nec("eval retrieval --data " + cache() + " --evaluator " + best + " --split test --json " +
                                      path("r.json"));
  ASSERT_EQ(table.exit_code, 0) << table.output;
  EXPECT_TRUE(contains(table.output, "| zoo_held_out |")) << table.output;
  EXPECT_TRUE(contains(table.output, "| all |")) << table.output;
  EXPECT_TRUE(fs::exists(path("r.json")));

  const std::string query = "retrieve \"a quadruped walks\" --db " + cache() + " --evaluator " + best + " -k 3";
  const CommandResult first = run_nec(query + " --view " + path("hits.html"));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_TRUE(contains(first.output, "indexed ")) << first.output;
  EXPECT_TRUE(contains(first.output, "| 3 | ")) << first.output;
  EXPECT_TRUE(fs::exists(path("hits.html")));
  const CommandResult second = run_nec(query);
  ASSERT_EQ(second.exit_code, 0) << second.output;
  EXPECT_FALSE(contains(second.output, "indexed ")) << "the stored index was not reused:\n" << second.output;
  // --save writes the matches as BVH with their captions, in the order of the table; never over files without --force.
  const CommandResult saved = run_nec(query + " --save " + path("found"));
  ASSERT_EQ(saved.exit_code, 0) << saved.output;
  EXPECT_TRUE(contains(saved.output, "wrote 3 clips to ")) << saved.output;
  for (int rank = 1; rank <= 3; ++rank) {
    const std::string stem = path("found/" + std::to_string(rank));
    const Clip clip = read_bvh(stem + ".bvh");
    EXPECT_GE(clip.motion.frame_count, 8);
    const std::string caption = read_file(stem + ".txt");
    ASSERT_FALSE(caption.empty());
    const std::string row = "| " + std::to_string(rank) + " | ";
    const size_t at = saved.output.find(row);
    ASSERT_NE(at, std::string::npos) << saved.output;
    const std::string line = saved.output.substr(at, saved.output.find('\n', at) - at);
    EXPECT_TRUE(contains(line, "| " + caption.substr(0, caption.size() - 1) + " |")) << line << " vs " << caption;
  }
  EXPECT_FALSE(fs::exists(path("found/4.bvh")));
  const CommandResult again = run_nec(query + " --save " + path("found"));
  EXPECT_EQ(again.exit_code, 1) << again.output;
  EXPECT_TRUE(contains(again.output, "1.bvh: exists; pass --force")) << again.output;
  EXPECT_EQ(run_nec(query + " --save " + path("found") + " --force").exit_code, 0);
  // The page is never overwritten; an empty caption and a missing evaluator are refused.
  const CommandResult page = run_nec(query + " --view " + path("hits.html"));
  EXPECT_EQ(page.exit_code, 2) << page.output;
  EXPECT_TRUE(contains(page.output, "exists; choose another --view file")) << page.output;
  const CommandResult empty = run_nec("retrieve \"?!\" --db " + cache() + " --evaluator " + best);
  EXPECT_EQ(empty.exit_code, 1) << empty.output;
  EXPECT_TRUE(contains(empty.output, "no letters in")) << empty.output;
  const CommandResult missing = run_nec("retrieve \"a dog\" --db " + cache() + " --evaluator " + path("none"));
  EXPECT_EQ(missing.exit_code, 1) << missing.output;
  EXPECT_TRUE(contains(missing.output, "nec train evaluator")) << missing.output;
  const CommandResult both = run_nec("retrieve \"a dog\" --motion x.bvh --db " + cache() + " --evaluator " + best);
  EXPECT_EQ(both.exit_code, 2) << both.output;
  // By the captions alone (--caption-weight 1) a clip's own long caption finds that clip first.
  const DatasetCache db = read_cache(cache());
  const CacheClip& asked = db.clips.at(db.clips.size() / 2);
  ASSERT_FALSE(asked.captions.empty());
  const CommandResult by_caption = run_nec("retrieve \"" + asked.captions.back() + "\" --db " + cache() + " --evaluator " +
                                           best + " -k 1 --caption-weight 1");
  ASSERT_EQ(by_caption.exit_code, 0) << by_caption.output;
  EXPECT_TRUE(contains(by_caption.output, "| 1 | ") && contains(by_caption.output, "| " + asked.id + " |")) << by_caption.output;
  const CommandResult weight = run_nec(query + " --caption-weight 1.5");
  EXPECT_EQ(weight.exit_code, 2) << weight.output;
  EXPECT_TRUE(contains(weight.output, "--caption-weight must be in [0, 1]")) << weight.output;

  // A clip of the cache's own files finds captions.
  const std::string clip = shared_folder() / "zoo/seen";
  std::string bvh;
  for (const auto& entry : fs::recursive_directory_iterator(clip)) {
    if (entry.path().extension() == ".bvh") {
      bvh = entry.path().string();
      break;
    }
  }
  const CommandResult by_motion = run_nec("retrieve --motion " + bvh + " --db " + cache() + " --evaluator " + best + " -k 2");
  ASSERT_EQ(by_motion.exit_code, 0) << by_motion.output;
  EXPECT_TRUE(contains(by_motion.output, "| 2 | ")) << by_motion.output;

  // nec eval t2m on the zoo's own files (captions in sidecars) as "generated" clips.
  const CommandResult t2m = run_nec("eval t2m --generated " + shared_folder() / "zoo/held_out" + " --reference " + cache() +
                                    " --evaluator " + best + " --json " + path("t2m.json"));
  ASSERT_EQ(t2m.exit_code, 0) << t2m.output;
  EXPECT_TRUE(contains(t2m.output, "| all |")) << t2m.output;
  EXPECT_TRUE(fs::exists(path("t2m.json")));
  const CommandResult nothing = run_nec("eval t2m --generated " + path("nothing") + " --reference " + cache() +
                                        " --evaluator " + best);
  EXPECT_EQ(nothing.exit_code, 1) << nothing.output;
}

}  // namespace
}  // namespace nec

// The GPT's commands end to end on a tiny zoo: nec train gpt (tokens stored
// beside the cache, checkpoints, --resume), nec generate onto a skeleton the
// models never saw (its names, channels and length; samples, seeds,
// several captions), and the errors a user sees.
#include "nec/gpt/checkpoint.h"
#include "nec/motion/bvh.h"
#include "nec/motion/files.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <filesystem>
#include <string>

namespace nec {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::contains;
using testing::run_nec;

class CliGpt : public testing::SharedFolderTest {
 protected:
  // A zoo cache (the spider held out), its piece model, a tiny OwO, tokenizer and GPT.
  static void SetUpTestSuite() {
    SharedFolderTest::SetUpTestSuite();
    const testing::TempDir& d = shared_folder();
    testing::make_captioned_zoo(d, 4, 6, "--val 0.2 --test 0.1");
    if (HasFatalFailure()) return;
    write_file_atomic(d / "tat.json", R"({"model": {"kind": "nec-rvq", "dim": 16, "blocks": 2, "attention_layers": 1,
      "heads": 2, "quantizer": {"layers": 2, "codebook_size": 16, "code_dim": 16}},
      "steps": 4, "batch_size": 4, "data": {"window_frames": 16}, "log_every": 2, "validate_every": 0,
      "checkpoint_every": 0, "seed": 1})");
    const CommandResult tat = run_nec("train tat --config " + d / "tat.json" + " --data " + d / "cache" + " --owo " +
                                      d / "owo" + " --out " + d / "tat" + " --threads 1");
    ASSERT_EQ(tat.exit_code, 0) << tat.output;
    write_file_atomic(d / "gpt.json", R"({
      "model": {"dim": 32, "layers": 2, "heads": 2, "feedforward": 64, "max_steps": 16,
                "text": {"word_dim": 0, "dim": 16, "heads": 2, "feedforward": 32, "layers": 1, "max_pieces": 128, "output_dim": 16}},
      "batch_size": 8, "steps": 6, "log_every": 2, "validate_every": 3, "checkpoint_every": 3, "seed": 2})");
    const CommandResult gpt = run_nec(train_gpt(d / "gpt"));
    ASSERT_EQ(gpt.exit_code, 0) << gpt.output;
    training_output() = gpt.output;
  }

  static std::string& training_output() {
    static std::string output;
    return output;
  }
  static std::string train_gpt(const std::string& out, const std::string& extra = "") {
    const testing::TempDir& d = shared_folder();
    return "train gpt --config " + d / "gpt.json" + " --data " + d / "cache" + " --tat " + d / "tat" + " --pieces " +
           d / "spm.model" + " --out " + out + " --threads 1 " + extra;
  }
  // The held-out spider's first clip: a skeleton no model saw.
  static std::string spider() { return testing::bvh_files_under(shared("zoo/held_out")).front(); }
  static std::string generate(const std::string& arguments) {
    return "generate " + arguments + " --model " + shared("gpt") + " --threads 1";
  }
};

TEST_F(CliGpt, TrainingStoresTheTokensOnceAndResumes) {
  const std::string& output = training_output();
  EXPECT_TRUE(contains(output, "stored in " + shared("cache") + "/gpt-tokens-")) << output;
  EXPECT_TRUE(contains(output, "validation at step 3: val_loss")) << output;
  const nlohmann::json config = nlohmann::json::parse(read_file(shared("gpt/config.json")));
  EXPECT_EQ(config["format"], "nec-gpt");
  EXPECT_EQ(config["training_step"], 6);
  EXPECT_EQ(config["gpt"]["codebook_layers"], 2);
  EXPECT_EQ(config["gpt"]["codebook_size"], 16);
  EXPECT_TRUE(fs::exists(shared("gpt/tat/owo/config.json")));
  EXPECT_TRUE(fs::exists(shared("gpt/pieces.model")));

  // A second run reads the stored tokens; a resumed copy goes on from step 6.
  fs::copy(shared("gpt"), path("gpt"), fs::copy_options::recursive);
  const CommandResult resumed = run_nec(train_gpt(path("gpt"), "--resume --steps 8"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(contains(resumed.output, "steps 7-8 of")) << resumed.output;
  EXPECT_FALSE(contains(resumed.output, "stored in")) << resumed.output;
  EXPECT_EQ(nlohmann::json::parse(read_file(path("gpt/config.json")))["training_step"], 8);
  // Into a finished checkpoint without --resume or --force: refused, nothing touched.
  const CommandResult again = run_nec(train_gpt(path("gpt")));
  EXPECT_EQ(again.exit_code, 1) << again.output;
}

// Two processes, each on its share of every batch, take the steps one process takes (without dropout or token
// corruption, whose draws depend on the share's shape). Tolerances as in test_cli_distributed.cpp: float sums in
// another order, turned into steps of up to the learning rate by Adam where a gradient is zero but for rounding.
TEST_F(CliGpt, TwoProcessesTakeTheStepsOfOne) {
  const std::string config = dir_.write("exact.json", R"({
    "model": {"dim": 32, "layers": 2, "heads": 2, "feedforward": 64, "max_steps": 16, "dropout": 0.0,
              "text": {"word_dim": 0, "dim": 16, "heads": 2, "feedforward": 32, "layers": 1, "max_pieces": 128,
                       "output_dim": 16, "dropout": 0.0, "piece_dropout": 0.0}},
    "optimizer": {"learning_rate": 0.003, "warmup_steps": 1},
    "token_keep": 1.0, "batch_size": 8, "steps": 4, "log_every": 1, "validate_every": 0, "checkpoint_every": 0, "seed": 3})");
  const std::string base = "train gpt --config " + config + " --data " + shared("cache") + " --tat " + shared("tat") +
                           " --pieces " + shared("spm.model") + " --threads 1 --out ";
  const CommandResult one = run_nec(base + path("one"));
  ASSERT_EQ(one.exit_code, 0) << one.output;
  const CommandResult two = run_nec(base + path("two") + " --nproc 2");
  ASSERT_EQ(two.exit_code, 0) << two.output;
  const auto loss = [](const std::string& output) {
    const std::string line = testing::last_line_starting(output, "step 4/4");
    return line.substr(line.find("loss"));
  };
  EXPECT_EQ(loss(one.output), loss(two.output));
  gpt::LoadedGpt a = gpt::load_gpt_checkpoint(path("one")), b = gpt::load_gpt_checkpoint(path("two"));
  const auto second = b.model->named_parameters();
  double largest = 0, sum = 0;
  int64_t count = 0;
  for (const auto& item : a.model->named_parameters()) {
    const at::Tensor gap = (item.value() - second[item.key()]).abs().to(torch::kDouble);
    largest = std::max(largest, gap.max().item<double>());
    sum += gap.sum().item<double>();
    count += gap.numel();
  }
  std::printf("1 vs 2 processes, 4 steps: parameters differ by %.3g on average, %.3g at most\n", sum / count, largest);
  EXPECT_LT(sum / count, 1e-6);
  EXPECT_LT(largest, 0.1 * 0.003 * 4);
}

TEST_F(CliGpt, GeneratesOnASkeletonNoModelSaw) {
  const std::string out = path("spider_walk.bvh");
  const CommandResult run = run_nec(generate("\"a spider walks forward\" --skeleton " + spider() + " -o " + out +
                                             " --seconds 1 --seed 3"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const Clip source = read_bvh(spider());
  const Clip made = read_bvh(out);
  EXPECT_EQ(made.motion.frame_count, 32);  // 1 s at 30 fps: 8 steps of 4 frames
  EXPECT_EQ(read_file(path("spider_walk.txt")), "a spider walks forward\n");  // what `nec eval t2m` reads
  ASSERT_EQ(made.skeleton.joint_count(), source.skeleton.joint_count());
  for (int j = 0; j < made.skeleton.joint_count(); ++j) {
    EXPECT_EQ(made.skeleton.names[j], source.skeleton.names[j]);
    EXPECT_EQ(made.skeleton.channels[j].euler_order(), source.skeleton.channels[j].euler_order());
  }
  // The same seed writes the same file; samples 1..K are seeds 3, 4, ...: the first is the one above.
  const std::string again = path("again.bvh");
  ASSERT_EQ(run_nec(generate("\"a spider walks forward\" --skeleton " + spider() + " -o " + again +
                             " --seconds 1 --seed 3")).exit_code, 0);
  EXPECT_EQ(read_file(again), read_file(out));
  const CommandResult many = run_nec(generate("\"a spider walks forward\" --skeleton " + spider() + " -o " +
                                              path("many.bvh") + " --seconds 1 --seed 3 --samples 2 --view " +
                                              path("many.html")));
  ASSERT_EQ(many.exit_code, 0) << many.output;
  EXPECT_EQ(read_file(path("many_1.bvh")), read_file(out));
  EXPECT_NE(read_file(path("many_2.bvh")), read_file(out));
  EXPECT_FALSE(fs::exists(path("many.bvh")));
  EXPECT_TRUE(fs::exists(path("many.html")));

  // Two captions: two segments of 1 s, one motion.
  const CommandResult two = run_nec(generate("\"a spider walks forward\" \"a spider turns left\" --skeleton " + spider() +
                                             " -o " + path("two.bvh") + " --seconds 1"));
  ASSERT_EQ(two.exit_code, 0) << two.output;
  EXPECT_EQ(read_bvh(path("two.bvh")).motion.frame_count, 64);
  // Progress a line per segment, in order (nec serve shows a running job's last line).
  const size_t first = two.output.find("segment 1/2: a spider walks forward\n");
  EXPECT_NE(first, std::string::npos) << two.output;
  const size_t second = two.output.find("segment 2/2: a spider turns left\n");
  EXPECT_NE(second, std::string::npos) << two.output;
  EXPECT_GT(second, first) << two.output;
  // One length per caption: 1 s and 0.5 s (8 + 4 steps of 4 frames); a count that fits neither is refused.
  const CommandResult each = run_nec(generate("\"a spider walks forward\" \"a spider turns left\" --skeleton " +
                                              spider() + " -o " + path("each.bvh") + " --seconds 1,0.5"));
  ASSERT_EQ(each.exit_code, 0) << each.output;
  EXPECT_EQ(read_bvh(path("each.bvh")).motion.frame_count, 48);
  const CommandResult three = run_nec(generate("\"a spider walks forward\" \"a spider turns left\" --skeleton " +
                                               spider() + " -o " + path("three.bvh") + " --seconds 1,1,1"));
  EXPECT_EQ(three.exit_code, 1);
  EXPECT_NE(three.output.find("gives 3 lengths for 2 captions"), std::string::npos) << three.output;
  const CommandResult bad = run_nec(generate("\"a spider walks\" --skeleton " + spider() + " -o " + path("bad.bvh") +
                                             " --seconds 1x"));
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.output.find("'1x' is not a length"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(path("three.bvh")) || fs::exists(path("bad.bvh")));
  // A rig exported in its rest pose (one frame, as Blender's exporter writes it for the add-on) is a skeleton too.
  const std::string posed = path("one_frame.bvh");
  write_bvh(posed, source.skeleton, source.motion.slice(0, 1));
  const CommandResult on_one = run_nec(generate("\"a spider walks\" --skeleton " + posed + " -o " + path("on_one.bvh") +
                                                " --seconds 1"));
  ASSERT_EQ(on_one.exit_code, 0) << on_one.output;
  EXPECT_EQ(read_bvh(path("on_one.bvh")).motion.frame_count, 32);
  const CommandResult onto_one = run_nec("transfer " + out + " --to " + posed + " -o " + path("onto_one.bvh") +
                                         " --model " + shared("gpt/tat") + " --threads 1");
  ASSERT_EQ(onto_one.exit_code, 0) << onto_one.output;
  EXPECT_EQ(read_bvh(path("onto_one.bvh")).motion.frame_count, 32);
  // Without --seconds the GPT ends the motion (at most max_steps - 1 = 15 steps).
  const CommandResult open = run_nec(generate("\"a spider walks\" --skeleton " + spider() + " -o " + path("open.bvh")));
  ASSERT_EQ(open.exit_code, 0) << open.output;
  const int frames = read_bvh(path("open.bvh")).motion.frame_count;
  EXPECT_GE(frames, 4 * 4);
  EXPECT_LE(frames, 15 * 4);
}

// The baselines' tokens carry a GPT too (the evaluation compares the three): NEC-VQ has one code per step, the
// zero-padding baseline reads no OwO embeddings, yet the GPT's skeleton features still come from its OwO.
TEST_F(CliGpt, TrainsAndGeneratesOnTheSentenceEncoder) {
  // The use-lite backbone with no text layers: no piece model, the sentence vector the one piece attended to.
  const std::string config = dir_.write("use.json", R"({
    "model": {"dim": 32, "layers": 2, "heads": 2, "feedforward": 64, "max_steps": 16,
              "text": {"backbone": "use-lite", "word_dim": 0, "dim": 16, "layers": 0, "output_dim": 16}},
    "batch_size": 8, "steps": 4, "log_every": 2, "validate_every": 2, "checkpoint_every": 0, "seed": 2})");
  const CommandResult train = run_nec("train gpt --config " + config + " --data " + shared("cache") + " --tat " +
                                      shared("tat") + " --threads 1 --out " + path("gpt-use"));
  ASSERT_EQ(train.exit_code, 0) << train.output;
  EXPECT_FALSE(fs::exists(fs::path(path("gpt-use")) / "pieces.model"));
  const std::string out = path("use_walk.bvh");
  const CommandResult run = run_nec("generate \"somebody strolls forward\" --skeleton " + spider() + " -o " + out +
                                    " --seconds 1 --seed 3 --model " + path("gpt-use") + " --threads 1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(read_bvh(out).skeleton.joint_count(), read_bvh(spider()).skeleton.joint_count());
}

TEST_F(CliGpt, TheBaselineTokenizersCarryAGpt) {
  const testing::TempDir& d = shared_folder();
  for (const std::string kind : {"nec-vq", "zero-pad-rvq"}) {
    const CommandResult tat = run_nec("train tat --config " + d / "tat.json" + " --kind " + kind + " --data " +
                                      d / "cache" + " --owo " + d / "owo" + " --out " + path(kind) + " --steps 2 --threads 1");
    ASSERT_EQ(tat.exit_code, 0) << kind << "\n" << tat.output;
    const CommandResult gpt = run_nec("train gpt --config " + d / "gpt.json" + " --data " + d / "cache" + " --tat " +
                                      path(kind) + " --pieces " + d / "spm.model" + " --out " + path("gpt-" + kind) +
                                      " --steps 2 --threads 1");
    ASSERT_EQ(gpt.exit_code, 0) << kind << "\n" << gpt.output;
    const nlohmann::json config = nlohmann::json::parse(read_file(path("gpt-" + kind + "/config.json")));
    EXPECT_EQ(config["gpt"]["codebook_layers"], kind == "nec-vq" ? 1 : 2) << kind;
    const std::string out = path(kind + ".bvh");
    const CommandResult made = run_nec("generate \"a spider walks forward\" --skeleton " + spider() + " -o " + out +
                                       " --seconds 1 --model " + path("gpt-" + kind) + " --threads 1");
    ASSERT_EQ(made.exit_code, 0) << kind << "\n" << made.output;
    EXPECT_EQ(read_bvh(out).motion.frame_count, 32) << kind;
  }
}

// The stance network's commands on the tiny zoo: nec train stance, nec eval stance (held-out spider against the
// bind pose kept), and generation that takes the stance by default, keeps the file's mean pose when asked, and
// refuses a stance that is not one.
TEST_F(CliGpt, GeneratesAroundTheStanceOfTheSkeleton) {
  const std::string stance = path("stance");
  const CommandResult trained = run_nec("train stance --data " + shared("cache") + " --out " + stance +
                                        " --steps 20 --batch 4 --frames 2 --threads 1");
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  EXPECT_TRUE(contains(trained.output, "step 20/20")) << trained.output;
  const CommandResult scored = run_nec("eval stance --model " + stance + " --data " + shared("cache") + " --json " +
                                       path("stance.json"));
  ASSERT_EQ(scored.exit_code, 0) << scored.output;
  EXPECT_TRUE(contains(scored.output, "zoo_held_out / file rest")) << scored.output;
  EXPECT_TRUE(contains(scored.output, "the bind pose kept as the stance")) << scored.output;
  const nlohmann::json scores = nlohmann::json::parse(read_file(path("stance.json")));
  ASSERT_TRUE(scores.is_array() && !scores.empty());
  EXPECT_GT(scores[0].at("bones").get<int>(), 0);

  // A one-frame rig: the stance decides its rest, so asking for the mean pose of its one frame writes another
  // motion from the same seed.
  const Clip source = read_bvh(spider());
  const std::string posed = path("stance_rig.bvh");
  write_bvh(posed, source.skeleton, source.motion.slice(0, 1));
  const std::string base = "\"a spider walks\" --skeleton " + posed + " --seconds 1 --seed 5 --stance " + stance;
  const CommandResult stood = run_nec(generate(base + " -o " + path("stood.bvh")));
  ASSERT_EQ(stood.exit_code, 0) << stood.output;
  const CommandResult mean = run_nec(generate("\"a spider walks\" --skeleton " + posed +
                                              " --seconds 1 --seed 5 --rest-from-motion -o " + path("mean.bvh")));
  ASSERT_EQ(mean.exit_code, 0) << mean.output;
  EXPECT_NE(read_file(path("stood.bvh")), read_file(path("mean.bvh")));
  EXPECT_EQ(read_bvh(path("stood.bvh")).skeleton.names, source.skeleton.names);

  const CommandResult both = run_nec(generate(base + " --rest-from-motion -o " + path("both.bvh")));
  EXPECT_EQ(both.exit_code, 2) << both.output;
  EXPECT_TRUE(contains(both.output, "exclude each other")) << both.output;
  const CommandResult foreign = run_nec(generate("\"a spider walks\" --skeleton " + posed + " --stance " +
                                                 shared("tat") + " -o " + path("foreign.bvh")));
  EXPECT_EQ(foreign.exit_code, 1) << foreign.output;
  EXPECT_TRUE(contains(foreign.output, "config.json")) << foreign.output;
  EXPECT_FALSE(fs::exists(path("both.bvh")) || fs::exists(path("foreign.bvh")));

  // Rigs the stance cannot do much with: a leg of joints lying on their parents and a body without limbs are
  // said and still move; a skeleton whose joints all overlap is refused with no output.
  Clip collapsed = source;
  const int leg = collapsed.skeleton.children(0).back();
  const auto in_leg = [&](int j) {
    while (j > leg) j = collapsed.skeleton.parents[j];
    return j == leg;
  };
  for (int j = leg; j < collapsed.skeleton.joint_count(); ++j) {
    if (in_leg(j)) collapsed.skeleton.offsets[j].setZero();
  }
  for (EndSite& site : collapsed.skeleton.end_sites) {
    if (in_leg(site.parent)) site.offset.setZero();
  }
  write_bvh(path("collapsed.bvh"), collapsed.skeleton, collapsed.motion.slice(0, 1));
  const std::string chain_header =
      "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
      " JOINT Spine\n {\n  OFFSET 0 {0} 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "  JOINT Head\n  {\n   OFFSET 0 {0} 0\n   CHANNELS 3 Zrotation Xrotation Yrotation\n"
      "   End Site\n   {\n    OFFSET 0 {0} 0\n   }\n  }\n }\n}\nMOTION\nFrames: 1\nFrame Time: 0.0333333\n"
      "0 0 0 0 0 0 0 0 0 0 0 0\n";
  const auto chain_of = [&](const std::string& length) {
    std::string text = chain_header;
    for (size_t at; (at = text.find("{0}")) != std::string::npos;) text.replace(at, 3, length);
    return text;
  };
  write_file_atomic(path("chain.bvh"), chain_of("10"));
  write_file_atomic(path("overlapping.bvh"), chain_of("0"));
  for (const auto& [rig, said] : {std::pair<std::string, std::string>{"collapsed", "lie on their parents"},
                                  {"chain", "one chain, no limbs"}}) {
    const CommandResult made = run_nec(generate("\"a spider walks\" --skeleton " + path(rig + ".bvh") +
                                                " --seconds 1 --stance " + stance + " -o " + path(rig + "_out.bvh")));
    ASSERT_EQ(made.exit_code, 0) << rig << "\n" << made.output;
    EXPECT_TRUE(contains(made.output, "note: " + path(rig + ".bvh") + ": ") && contains(made.output, said))
        << rig << "\n" << made.output;
    EXPECT_GT(read_bvh(path(rig + "_out.bvh")).motion.frame_count, 1) << rig;
  }
  const CommandResult overlapping = run_nec(generate("\"a spider walks\" --skeleton " + path("overlapping.bvh") +
                                                     " --stance " + stance + " -o " + path("overlapping_out.bvh")));
  EXPECT_EQ(overlapping.exit_code, 1) << overlapping.output;
  EXPECT_TRUE(contains(overlapping.output, "overlapping.bvh") && contains(overlapping.output, "zero size"))
      << overlapping.output;
  EXPECT_FALSE(fs::exists(path("overlapping_out.bvh")));
}

TEST_F(CliGpt, BadInputGetsOneLineAndNoOutput) {
  const std::string out = path("out.bvh");
  const auto expect_refused = [&](const std::string& arguments, const std::string& message) {
    const CommandResult run = run_nec(arguments);
    EXPECT_EQ(run.exit_code, 1) << arguments << "\n" << run.output;
    EXPECT_TRUE(contains(run.output, message)) << arguments << "\n" << run.output;
    EXPECT_FALSE(fs::exists(out)) << arguments;
  };
  expect_refused(generate("\"\" --skeleton " + spider() + " -o " + out), "empty");
  expect_refused(generate("\"!! ??\" --skeleton " + spider() + " -o " + out), "letter");
  expect_refused(generate("\"a spider walks\" --skeleton " + path("none.bvh") + " -o " + out), "none.bvh");
  expect_refused(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out + " --seconds 0"), "--seconds");
  expect_refused(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out + " --seconds 999"), "--seconds");
  expect_refused("generate \"a spider walks\" --skeleton " + spider() + " -o " + out + " --model " + shared("tat"),
                 "not a GPT checkpoint");
  const CommandResult no_folder = run_nec(generate("\"a spider walks\" --skeleton " + spider() + " -o " + path("none/x.bvh")));
  EXPECT_EQ(no_folder.exit_code, 1) << no_folder.output;
  EXPECT_TRUE(contains(no_folder.output, "its folder does not exist")) << no_folder.output;
  // An existing output is not overwritten without --force.
  write_file_atomic(out, "mine");
  const CommandResult kept = run_nec(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out));
  EXPECT_EQ(kept.exit_code, 1) << kept.output;
  EXPECT_EQ(read_file(out), "mine");
  EXPECT_EQ(run_nec(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out + " --force --seconds 1")).exit_code, 0);
  EXPECT_NE(read_file(out), "mine");
}

}  // namespace
}  // namespace nec

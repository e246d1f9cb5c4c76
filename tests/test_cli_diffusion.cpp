// The diffusion model's commands end to end on a tiny zoo: nec train
// diffusion in two stages (checkpoints, --resume, the pose model frozen in
// the motion stage, two processes taking the steps of one), nec generate
// --model DIFFUSION onto a skeleton the models never saw (its names,
// channels and length; samples and seeds; several captions in overlapping
// windows), and the errors a user sees.
#include "nec/diffusion/checkpoint.h"
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
using testing::largest_rotation_difference;
using testing::run_nec;

constexpr const char* kPoseConfig = R"({
  "model": {"dim": 16, "heads": 2, "layers": 1, "feedforward": 32, "max_frames": 24, "noise_steps": 100,
            "text": {"word_dim": 0, "dim": 16, "heads": 2, "feedforward": 32, "layers": 1, "max_pieces": 128,
                     "output_dim": 16, "dropout": 0.0, "piece_dropout": 0.0}},
  "data": {"window_frames": 16}, "pose_frames": 2,
  "batch_size": 4, "steps": 4, "log_every": 2, "validate_every": 2, "checkpoint_every": 0, "seed": 1})";
constexpr const char* kMotionConfig = R"({
  "data": {"window_frames": 16}, "optimizer": {"learning_rate": 0.003, "warmup_steps": 1},
  "batch_size": 4, "steps": 4, "log_every": 1, "validate_every": 0, "checkpoint_every": 0, "seed": 2})";

class CliDiffusion : public testing::SharedFolderTest {
 protected:
  // A zoo cache (the spider held out), its piece model, a tiny OwO, and both stages of a tiny diffusion model.
  static void SetUpTestSuite() {
    SharedFolderTest::SetUpTestSuite();
    const testing::TempDir& d = shared_folder();
    testing::make_captioned_zoo(d, 4, 8, "--val 0.2 --test 0.1");
    if (HasFatalFailure()) return;
    write_file_atomic(d / "pose.json", kPoseConfig);
    write_file_atomic(d / "motion.json", kMotionConfig);
    const CommandResult pose = run_nec(train("pose", d / "pose", "--owo " + d / "owo" + " --pieces " + d / "spm.model"));
    ASSERT_EQ(pose.exit_code, 0) << pose.output;
    outputs()[0] = pose.output;
    const CommandResult motion = run_nec(train("motion", d / "motion", "--pose " + d / "pose"));
    ASSERT_EQ(motion.exit_code, 0) << motion.output;
    outputs()[1] = motion.output;
  }

  static std::array<std::string, 2>& outputs() {
    static std::array<std::string, 2> text;
    return text;
  }
  static std::string train(const std::string& stage, const std::string& out, const std::string& extra) {
    const testing::TempDir& d = shared_folder();
    return "train diffusion --stage " + stage + " --config " + d / (stage + ".json") + " --data " + d / "cache" +
           " --out " + out + " --threads 1 " + extra;
  }
  // The held-out spider's first clip: a skeleton no model saw.
  static std::string spider() { return testing::bvh_files_under(shared("zoo/held_out")).front(); }
  static std::string generate(const std::string& arguments) {
    return "generate " + arguments + " --model " + shared("motion") + " --threads 1 --steps 4";
  }
};

TEST_F(CliDiffusion, TwoStagesTrainFreezeThePoseModelAndResume) {
  EXPECT_TRUE(contains(outputs()[0], "validation at step 2: val_loss")) << outputs()[0];
  const nlohmann::json pose = nlohmann::json::parse(read_file(shared("pose/config.json")));
  EXPECT_EQ(pose["format"], "nec-diffusion");
  EXPECT_EQ(pose["stage"], "pose");
  EXPECT_EQ(pose["denoiser"]["skeleton_dim"], 16);  // from the OwO encoder
  const nlohmann::json motion = nlohmann::json::parse(read_file(shared("motion/config.json")));
  EXPECT_EQ(motion["stage"], "motion");
  EXPECT_EQ(motion["training_step"], 4);
  EXPECT_TRUE(fs::exists(shared("motion/owo/config.json")));
  EXPECT_TRUE(fs::exists(shared("motion/pieces.model")));

  // The motion stage changed the temporal blocks only.
  diffusion::LoadedDiffusion a = diffusion::load_diffusion_checkpoint(shared("pose"));
  diffusion::LoadedDiffusion b = diffusion::load_diffusion_checkpoint(shared("motion"));
  const auto after = b.model->named_parameters();
  double pose_change = 0, temporal_change = 0;
  for (const auto& item : a.model->named_parameters()) {
    const double change = (item.value() - after[item.key()]).abs().max().item<double>();
    const bool temporal = item.key().rfind("temporal.", 0) == 0 || item.key().rfind("frame_in.", 0) == 0;
    (temporal ? temporal_change : pose_change) = std::max(temporal ? temporal_change : pose_change, change);
  }
  EXPECT_EQ(pose_change, 0.0);
  EXPECT_GT(temporal_change, 0.0);

  // A resumed copy goes on from step 4; the wrong stage or a "model" in the motion config is refused.
  fs::copy(shared("motion"), path("motion"), fs::copy_options::recursive);
  const CommandResult resumed = run_nec(train("motion", path("motion"), "--resume --steps 6"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(contains(resumed.output, "steps 5-6 of")) << resumed.output;
  EXPECT_EQ(nlohmann::json::parse(read_file(path("motion/config.json")))["training_step"], 6);
  const CommandResult wrong = run_nec(train("pose", path("motion"), "--resume --steps 8"));
  EXPECT_EQ(wrong.exit_code, 1) << wrong.output;
  EXPECT_TRUE(contains(wrong.output, "--stage motion")) << wrong.output;
  const CommandResult from_motion = run_nec(train("motion", path("again"), "--pose " + shared("motion")));
  EXPECT_EQ(from_motion.exit_code, 1) << from_motion.output;
  EXPECT_TRUE(contains(from_motion.output, "pose stage's checkpoint")) << from_motion.output;
  const std::string with_model = dir_.write("with_model.json", kPoseConfig);
  const CommandResult refused = run_nec("train diffusion --stage motion --config " + with_model + " --data " +
                                        shared("cache") + " --pose " + shared("pose") + " --out " + path("x"));
  EXPECT_EQ(refused.exit_code, 1) << refused.output;
  EXPECT_TRUE(contains(refused.output, "remove \"model\"")) << refused.output;
  EXPECT_FALSE(fs::exists(path("x")));
}

// Two processes, each on its share of every batch, take the steps one process takes: every item draws its
// timestep, noise and frames from its place in the whole batch. Tolerances as in test_cli_gpt.cpp.
TEST_F(CliDiffusion, TwoProcessesTakeTheStepsOfOne) {
  const CommandResult one = run_nec(train("motion", path("one"), "--pose " + shared("pose")));
  ASSERT_EQ(one.exit_code, 0) << one.output;
  const CommandResult two = run_nec(train("motion", path("two"), "--pose " + shared("pose") + " --nproc 2"));
  ASSERT_EQ(two.exit_code, 0) << two.output;
  const auto loss = [](const std::string& output) {
    const std::string line = testing::last_line_starting(output, "step 4/4");
    return line.substr(line.find("loss"));
  };
  EXPECT_EQ(loss(one.output), loss(two.output));
  diffusion::LoadedDiffusion a = diffusion::load_diffusion_checkpoint(path("one"));
  diffusion::LoadedDiffusion b = diffusion::load_diffusion_checkpoint(path("two"));
  const auto second = b.model->named_parameters();
  double largest = 0;
  for (const auto& item : a.model->named_parameters()) {
    largest = std::max(largest, (item.value() - second[item.key()]).abs().max().item<double>());
  }
  EXPECT_LT(largest, 0.1 * 0.003 * 4);
}

TEST_F(CliDiffusion, GeneratesOnASkeletonNoModelSaw) {
  const std::string out = path("spider_walk.bvh");
  const CommandResult run = run_nec(generate("\"a spider walks forward\" --skeleton " + spider() + " -o " + out +
                                             " --seconds 0.5 --seed 3"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const Clip source = read_bvh(spider());
  const Clip made = read_bvh(out);
  EXPECT_EQ(made.motion.frame_count, 15);  // 0.5 s at 30 fps
  EXPECT_EQ(read_file(path("spider_walk.txt")), "a spider walks forward\n");
  ASSERT_EQ(made.skeleton.joint_count(), source.skeleton.joint_count());
  for (int j = 0; j < made.skeleton.joint_count(); ++j) {
    EXPECT_EQ(made.skeleton.names[j], source.skeleton.names[j]);
    EXPECT_EQ(made.skeleton.channels[j].euler_order(), source.skeleton.channels[j].euler_order());
  }
  // The same seed writes the same file; samples 1..K are seeds 3, 4, ...
  const std::string again = path("again.bvh");
  ASSERT_EQ(run_nec(generate("\"a spider walks forward\" --skeleton " + spider() + " -o " + again +
                             " --seconds 0.5 --seed 3")).exit_code, 0);
  EXPECT_EQ(read_file(again), read_file(out));
  const CommandResult many = run_nec(generate("\"a spider walks forward\" --skeleton " + spider() + " -o " +
                                              path("many.bvh") + " --seconds 0.5 --seed 3 --samples 2"));
  ASSERT_EQ(many.exit_code, 0) << many.output;
  // In a batch the matrix products may round differently in the last digit: the same motion, not the same bytes.
  // (This tiny model hardly depends on its noise, so seed 4 is checked against sample 2 in test_diffusion.)
  EXPECT_LT(largest_rotation_difference(read_bvh(path("many_1.bvh")).motion, made.motion), 1e-4);
  EXPECT_EQ(read_bvh(path("many_2.bvh")).motion.frame_count, 15);

  // Two captions of 1 s each, longer than the model's 24-frame window: overlapping windows, one motion.
  const CommandResult two = run_nec(generate("\"a spider walks forward\" \"a spider turns left\" --skeleton " + spider() +
                                             " -o " + path("two.bvh") + " --seconds 1"));
  ASSERT_EQ(two.exit_code, 0) << two.output;
  EXPECT_EQ(read_bvh(path("two.bvh")).motion.frame_count, 60);
  // Progress a line per denoising step (nec serve shows a running job's last line).
  EXPECT_NE(two.output.find("denoising step 1/4\n"), std::string::npos) << two.output;
  const size_t last = two.output.find("denoising step 4/4\n");
  EXPECT_NE(last, std::string::npos) << two.output;
  EXPECT_GT(last, two.output.find("denoising step 3/4\n")) << two.output;
  // Without --seconds: one window.
  ASSERT_EQ(run_nec(generate("\"a spider walks\" --skeleton " + spider() + " -o " + path("open.bvh"))).exit_code, 0);
  EXPECT_EQ(read_bvh(path("open.bvh")).motion.frame_count, 24);
}

TEST_F(CliDiffusion, TrainsAndGeneratesOnTheSentenceEncoder) {
  // The use-lite backbone with no text layers: no --pieces, no piece model in either stage's checkpoint.
  const testing::TempDir& d = shared_folder();
  std::string pose_config = kPoseConfig;
  const std::string text = R"("text": {"word_dim": 0, "dim": 16, "heads": 2, "feedforward": 32, "layers": 1, "max_pieces": 128,
                     "output_dim": 16, "dropout": 0.0, "piece_dropout": 0.0})";
  ASSERT_NE(pose_config.find(text), std::string::npos);
  pose_config.replace(pose_config.find(text), text.size(),
                      R"("text": {"backbone": "use-lite", "word_dim": 0, "dim": 16, "layers": 0, "output_dim": 16})");
  const std::string pose_path = dir_.write("use_pose.json", pose_config);
  const std::string base = "train diffusion --data " + d / "cache" + " --threads 1 ";
  const CommandResult pose = run_nec(base + "--stage pose --config " + pose_path + " --owo " + d / "owo" + " --out " + path("use-pose"));
  ASSERT_EQ(pose.exit_code, 0) << pose.output;
  const CommandResult motion = run_nec(base + "--stage motion --config " + d / "motion.json" + " --pose " +
                                       path("use-pose") + " --out " + path("use-motion"));
  ASSERT_EQ(motion.exit_code, 0) << motion.output;
  EXPECT_FALSE(fs::exists(fs::path(path("use-motion")) / "pieces.model"));
  const std::string out = path("use_walk.bvh");
  const CommandResult run = run_nec("generate \"somebody strolls forward\" --skeleton " + spider() + " -o " + out +
                                    " --seconds 1 --seed 3 --model " + path("use-motion") + " --threads 1 --steps 4");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(read_bvh(out).skeleton.joint_count(), read_bvh(spider()).skeleton.joint_count());
}

TEST_F(CliDiffusion, BadInputGetsOneLineAndNoOutput) {
  const std::string out = path("out.bvh");
  // Exit 1 for bad input, 2 for options that do not go together.
  const auto expect_refused = [&](const std::string& arguments, const std::string& message, int code = 1) {
    const CommandResult run = run_nec(arguments);
    EXPECT_EQ(run.exit_code, code) << arguments << "\n" << run.output;
    EXPECT_TRUE(contains(run.output, message)) << arguments << "\n" << run.output;
    EXPECT_FALSE(fs::exists(out)) << arguments;
  };
  expect_refused(generate("\"\" --skeleton " + spider() + " -o " + out), "empty");
  expect_refused(generate("\"a spider walks\" --skeleton " + path("none.bvh") + " -o " + out), "none.bvh");
  expect_refused(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out + " --top-k 5"), "GPT models only", 2);
  expect_refused(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out + " --guidance 0.5"), "guidance", 2);
  expect_refused(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out + " --solver euler"), "dpm++ or ddim", 2);
  expect_refused(generate("\"a spider walks\" --skeleton " + spider() + " -o " + out + " --spacing log"), "quadratic or uniform", 2);
  expect_refused("generate \"a spider walks\" --skeleton " + spider() + " -o " + out + " --model " + shared("pose"),
                 "pose-stage");
  expect_refused("generate \"a spider walks\" --skeleton " + spider() + " -o " + out + " --model " + shared("owo"),
                 "not a GPT checkpoint");
  expect_refused("generate \"a spider walks\" --skeleton " + spider() + " -o " + out + " --model " + shared("motion") +
                     " --steps 1000",
                 "noise steps", 2);
}

}  // namespace
}  // namespace nec

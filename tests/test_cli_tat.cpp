// The tokenizer commands end to end on a tiny zoo: nec train tat (checkpoints,
// --resume, baselines), encode, decode, transfer and eval recon, and their
// errors on bad input.
#include "nec/assets/asset_reader.h"
#include "nec/motion/bvh.h"
#include "nec/motion/clip_file.h"
#include "nec/motion/files.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"
#include "nec/fitting/transfer_check.h"
#include "nec/tat/tokens.h"
#include "test_support.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>

namespace nec {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::last_line_starting;
using testing::contains;
using testing::run_nec;

constexpr const char* kOwoConfig = R"({
  "encoder": {"name_dim": 0, "dim": 16, "layers": 1, "heads": 2, "edge_dim": 8},
  "pretrain": {"pairs_per_skeleton": 16},
  "optimizer": {"learning_rate": 0.003, "warmup_steps": 2},
  "data": {"held_out": ["spider"], "poses_per_skeleton": 4},
  "names": false, "batch_size": 4, "steps": 4, "log_every": 2, "validate_every": 4, "checkpoint_every": 4, "seed": 3
})";

std::string tat_config(double learning_rate = 3e-3) {
  return R"({"model": {"kind": "nec-rvq", "dim": 16, "blocks": 2, "attention_layers": 1, "heads": 2,
  "quantizer": {"layers": 2, "codebook_size": 16, "code_dim": 16}},
  "optimizer": {"learning_rate": )" + std::to_string(learning_rate) + R"(, "final_lr_fraction": 0.0, "warmup_steps": 2},
  "steps": 6,
  "batch_size": 4, "data": {"window_frames": 16}, "log_every": 2, "validate_every": 3, "validation_batches": 1,
  "checkpoint_every": 3, "seed": 1})";
}

class CliTat : public testing::SharedFolderTest {
 protected:
  // One zoo, cache, OwO encoder and trained tokenizer for every test.
  static void SetUpTestSuite() {
    SharedFolderTest::SetUpTestSuite();
    const testing::TempDir& d = shared_folder();
    // The zoo's first actions, so that its clips stay what these tests were written for as the zoo grows.
    const CommandResult zoo = run_nec("zoo --out " + d / "zoo" + " --creatures 9 --clips-per-creature 2 --seconds 2 "
                                      "--seed 5 --hold-out spider --quiet --actions idle,walk,trot,run,gallop,turn,jump,"
                                      "sit,lie_down,attack,slither,swim,fly,glide,take_off,flap_wings,wave,raise_hands,"
                                      "point,clap,bow,crouch,kick");
    ASSERT_EQ(zoo.exit_code, 0) << zoo.output;
    const CommandResult prepare = run_nec("prepare zoo=" + d / "zoo/seen" + " held=" + d / "zoo/held_out" +
                                          " --hold-out-dataset held --val 0.2 --test 0.2 -o " + d / "cache" + " --quiet");
    ASSERT_EQ(prepare.exit_code, 0) << prepare.output;
    const CommandResult owo = run_nec("train owo --config " + d.write("owo.json", kOwoConfig) + " --data " +
                                      d / "cache" + " --out " + d / "owo" + " --no-names --threads 1");
    ASSERT_EQ(owo.exit_code, 0) << owo.output;
    const CommandResult tat = run_nec("train tat --config " + d.write("tat.json", tat_config()) + " --data " +
                                      d / "cache" + " --owo " + d / "owo" + " --out " + d / "tat" + " --threads 1");
    ASSERT_EQ(tat.exit_code, 0) << tat.output;
  }
  // A zoo clip of creature `index` (c000 ...), e.g. clip("c001") for the quadruped.
  static std::string zoo_clip(const std::string& creature_prefix) {
    for (const std::string& file : testing::bvh_files_under(shared("zoo"))) {
      if (contains(fs::path(file).filename().string(), creature_prefix)) return file;
    }
    return "";
  }
};

TEST_F(CliTat, TrainingWritesACheckpointAndResumes) {
  const nlohmann::json config = nlohmann::json::parse(read_file(shared("tat/config.json")));
  EXPECT_EQ(config["format"], "nec-tat");
  EXPECT_EQ(config["training_step"], 6);
  EXPECT_TRUE(fs::exists(shared("tat/owo/config.json")));
  EXPECT_TRUE(fs::exists(shared("tat/optimizer.pt")));

  // Resume a copy to a later step: it starts at 6, not 0.
  fs::copy(shared("tat"), path("tat"), fs::copy_options::recursive);
  const CommandResult resumed = run_nec("train tat --config " + shared("tat.json") + " --data " + shared("cache") +
                                        " --out " + path("tat") + " --resume --steps 8 --threads 1");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(contains(resumed.output, "step 8/8")) << resumed.output;
  EXPECT_FALSE(contains(resumed.output, "step 2/8")) << resumed.output;
  EXPECT_EQ(nlohmann::json::parse(read_file(path("tat/config.json")))["training_step"], 8);

  // A different model config cannot resume it.
  const CommandResult mismatch = run_nec("train tat --config " + shared("tat.json") + " --kind nec-vq --data " +
                                         shared("cache") + " --out " + path("tat") + " --resume --steps 9 --threads 1");
  EXPECT_EQ(mismatch.exit_code, 1) << mismatch.output;
  EXPECT_TRUE(contains(mismatch.output, "differs")) << mismatch.output;
}

TEST_F(CliTat, TheSameSeedTrainsTheSameModel) {
  auto train = [&](const nlohmann::json& config, const std::string& out, const std::string& extra) {
    return run_nec("train tat --config " + dir_.write(out + ".json", config.dump()) + " --data " + shared("cache") +
                   " --owo " + shared("owo") + " --out " + path(out) + " --threads 1 " + extra);
  };
  auto seeded = [&](const std::string& out, int seed) {
    nlohmann::json config = nlohmann::json::parse(tat_config());
    config["seed"] = seed;
    const CommandResult run = train(config, out, "--steps 4");
    EXPECT_EQ(run.exit_code, 0) << run.output;
    // The validation reports how much of the joints' turning the decoded clips keep: some, after 3 steps.
    const std::string validation = last_line_starting(run.output, "validation at step 3:");
    const size_t kept = validation.find("val_turning_kept ");
    EXPECT_NE(kept, std::string::npos) << run.output;
    if (kept != std::string::npos) {
      EXPECT_GT(std::stod(validation.substr(kept + 17)), 0.0) << validation;
      EXPECT_LT(std::stod(validation.substr(kept + 17)), 3.0) << validation;
    }
    return last_line_starting(run.output, "step 4/4");
  };
  auto losses = [](const std::string& line) { return line.substr(line.find("loss")); };
  const std::string first = seeded("first", 1), again = seeded("again", 1), other = seeded("other", 2);
  ASSERT_FALSE(first.empty());
  EXPECT_EQ(losses(first), losses(again));
  EXPECT_NE(losses(first), losses(other));

  // With a constant learning rate, a run stopped at step 2 and resumed to 4 takes the steps of one that never stopped.
  nlohmann::json constant = nlohmann::json::parse(tat_config());
  constant["optimizer"]["final_lr_fraction"] = 1.0;
  constant["optimizer"]["warmup_steps"] = 0;
  constant["checkpoint_every"] = 2;
  auto run = [&](const std::string& out, const std::string& extra) { return train(constant, out, extra); };
  const CommandResult straight = run("straight", "--steps 4");
  ASSERT_EQ(straight.exit_code, 0) << straight.output;
  ASSERT_EQ(run("stopped", "--steps 2").exit_code, 0);
  const CommandResult resumed = run("stopped", "--steps 4 --resume");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_EQ(losses(last_line_starting(resumed.output, "step 4/4")),
            losses(last_line_starting(straight.output, "step 4/4")));
}

TEST_F(CliTat, BaselinesTrainInTheSameLoop) {
  for (const char* kind : {"nec-vq", "zero-pad-rvq"}) {
    const CommandResult run = run_nec("train tat --config " + shared("tat.json") + " --kind " + kind + " --data " +
                                      shared("cache") + " --owo " + shared("owo") + " --out " + path(kind) +
                                      " --steps 2 --threads 1");
    ASSERT_EQ(run.exit_code, 0) << kind << "\n" << run.output;
    const nlohmann::json config = nlohmann::json::parse(read_file(path(std::string(kind) + "/config.json")));
    EXPECT_EQ(config["tokenizer"]["kind"], kind);
    if (std::string(kind) == "nec-vq") {
      EXPECT_EQ(config["tokenizer"]["quantizer"]["layers"], 1);
    }
    if (std::string(kind) == "zero-pad-rvq") {
      EXPECT_GT(config["tokenizer"]["max_joints"].get<int>(), 0);
    }
  }
}

TEST_F(CliTat, NonFiniteLossStopsTraining) {
  const std::string config = dir_.write("nan.json", tat_config(1e30));
  const CommandResult run = run_nec("train tat --config " + config + " --data " + shared("cache") + " --owo " +
                                    shared("owo") + " --out " + path("nan") + " --steps 6 --threads 1");
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_TRUE(contains(run.output, "training stopped at step")) << run.output;
}

TEST_F(CliTat, EncodeDecodeOntoAnotherSkeletonKeepsItsNamesAndChannels) {
  const std::string source = zoo_clip("c000_biped");
  const std::string target = zoo_clip("c001_quadruped");
  ASSERT_FALSE(source.empty());
  ASSERT_FALSE(target.empty());
  const std::string tokens = path("walk.tokens.json");
  const CommandResult encode = run_nec("encode " + source + " --model " + shared("tat") + " -o " + tokens + " --threads 1");
  ASSERT_EQ(encode.exit_code, 0) << encode.output;
  const tat::TokenFile file = tat::read_tokens(tokens);
  const Clip source_clip = read_bvh(source);
  EXPECT_EQ(file.frames, source_clip.motion.frame_count);  // the zoo is at 30 fps, like the model
  EXPECT_EQ(file.steps(), (file.frames + 3) / 4);
  EXPECT_EQ(file.layers, 2);
  EXPECT_EQ(file.source_joints, source_clip.skeleton.joint_count());

  const std::string out = path("dog_walk.bvh");
  const CommandResult decode = run_nec("decode " + tokens + " --skeleton " + target + " --model " + shared("tat") +
                                       " -o " + out + " --threads 1");
  ASSERT_EQ(decode.exit_code, 0) << decode.output;
  const Clip target_clip = read_bvh(target);
  const Clip decoded = read_bvh(out);
  EXPECT_EQ(decoded.motion.frame_count, file.frames);
  ASSERT_EQ(decoded.skeleton.joint_count(), target_clip.skeleton.joint_count());
  for (int j = 0; j < decoded.skeleton.joint_count(); ++j) {
    EXPECT_EQ(decoded.skeleton.names[j], target_clip.skeleton.names[j]);
    EXPECT_EQ(decoded.skeleton.channels[j].euler_order(), target_clip.skeleton.channels[j].euler_order());
    if (j > 0) {
      EXPECT_NEAR((decoded.skeleton.offsets[j] - target_clip.skeleton.offsets[j]).norm(), 0.0, 1e-4);
    }
  }

  const auto transfer = [&](const std::string& name, const std::string& flags) {
    const std::string out_path = path(name);
    const CommandResult run = run_nec("transfer " + source + " --to " + target + " --model " + shared("tat") + " -o " +
                                      out_path + " --threads 1" + flags);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return out_path;
  };
  // transfer = encode + decode, and then turned to face as the source does, put on the floor where it stands and
  // its gliding feet stepped in the source's rhythm (decode, without a source, settles the body onto the floor
  // instead).
  const std::string decoded_height = path("decoded_height.bvh");
  ASSERT_EQ(run_nec("decode " + tokens + " --skeleton " + target + " --model " + shared("tat") + " -o " + decoded_height +
                    " --threads 1 --free-height").exit_code, 0);
  EXPECT_EQ(read_file(transfer("as_decoded.bvh", " --free-heading --free-height --free-steps")), read_file(decoded_height));
  const Clip followed = read_bvh(transfer("followed.bvh", ""));
  const Clip followed_free_feet = read_bvh(transfer("followed_free_feet.bvh", " --free-feet --free-steps"));
  const Clip free = read_bvh(transfer("free.bvh", " --free-feet --free-steps --free-heading"));
  ASSERT_EQ(followed.motion.frame_count, decoded.motion.frame_count);
  ASSERT_EQ(free.motion.frame_count, decoded.motion.frame_count);
  // Facing is followed by turning the root (and its path) only.
  double largest_turn = 0.0;
  for (int t = 0; t < free.motion.frame_count; ++t) {
    largest_turn = std::max(largest_turn, followed_free_feet.motion.rotation(t, 0).angularDistance(free.motion.rotation(t, 0)));
    for (int j = 1; j < free.motion.joint_count; ++j) {
      EXPECT_LT(followed_free_feet.motion.rotation(t, j).angularDistance(free.motion.rotation(t, j)), 1e-6) << t;
    }
  }
  EXPECT_GT(largest_turn, 1e-3);
  const Clip source_clip_normalized = preprocess(source_clip, source).clip;
  const double followed_error =
      std::abs(check_transfer(source_clip_normalized, preprocess(followed_free_feet, "followed").clip).heading_difference);
  const double free_error = std::abs(check_transfer(source_clip_normalized, preprocess(free, "free").clip).heading_difference);
  std::printf("heading change error: followed %.2f, as decoded %.2f deg\n", followed_error, free_error);
  // The tiny model's decoded drift depends on its 6 training steps (33 deg in the files' own rest poses, 14 in
  // the canonical rest); steering takes out most of it, to about 4 (its precision on known drifts is
  // tests/test_follow_heading.cpp's).
  EXPECT_LT(followed_error, 5.0);
  EXPECT_LT(followed_error, 0.4 * free_error);

  // Feet are stepped and pinned by turning leg joints only: with --free-feet --free-steps the root moves and
  // turns the same.
  for (int t = 0; t < followed.motion.frame_count; ++t) {
    EXPECT_LT((followed.motion.translation(t, 0) - followed_free_feet.motion.translation(t, 0)).norm(), 1e-9) << t;
    EXPECT_LT(followed.motion.rotation(t, 0).angularDistance(followed_free_feet.motion.rotation(t, 0)), 1e-9) << t;
  }
}

// A rigged asset as the target: -o .glb writes the same motion as -o .bvh, as the asset's first animation
// named after the source file (the GLB read back by nec, joint by joint).
TEST_F(CliTat, TransferOntoARiggedAssetWritesTheSameMotionAsGlb) {
  const std::string wuson = "/usr/share/assimp/models/X/Testwuson.X";
  if (!fs::exists(wuson)) GTEST_SKIP() << "assimp-testmodels is not installed";
  assets::register_asset_formats();
  const std::string source = zoo_clip("c000_biped");
  ASSERT_FALSE(source.empty());
  for (const char* ext : {".bvh", ".glb"}) {
    const CommandResult run = run_nec("transfer " + source + " --to " + wuson + " --model " + shared("tat") +
                                      " -o " + path(std::string("wuson") + ext) + " --threads 1");
    ASSERT_EQ(run.exit_code, 0) << run.output;
  }
  const Clip bvh = read_bvh(path("wuson.bvh"));
  const Clip glb = read_clip(path("wuson.glb"));
  EXPECT_EQ(glb.name, fs::path(source).filename().string());
  ASSERT_EQ(glb.motion.frame_count, bvh.motion.frame_count);
  const Pose a = forward_kinematics(bvh.skeleton, bvh.motion);
  const Pose b = forward_kinematics(glb.skeleton, glb.motion);
  double worst = 0.0;
  int compared = 0;
  for (int j = 0; j < bvh.skeleton.joint_count(); ++j) {
    const int k = glb.skeleton.find(bvh.skeleton.names[j]);
    if (k < 0) continue;
    ++compared;
    for (int t = 0; t < bvh.motion.frame_count; ++t) worst = std::max(worst, (a.position(t, j) - b.position(t, k)).norm());
  }
  EXPECT_GE(compared, bvh.skeleton.joint_count() - 1);
  EXPECT_LT(worst, 1e-4 * bvh.skeleton.diameter());
}

// The same clips written in three joint-orient conventions (as authored, every bone along its parent's +X as
// Maya exports, a random frame per joint): preprocessing takes them to one canonical rest, so the tokens, and
// the transfers from them and onto them, are the same; output keeps the target file's own convention.
TEST_F(CliTat, JointFrameConventionsChangeNeitherTokensNorTransfers) {
  const std::string authored_source = zoo_clip("c000_biped");
  const std::string authored_target = zoo_clip("c001_quadruped");
  ASSERT_FALSE(authored_source.empty());
  ASSERT_FALSE(authored_target.empty());
  const auto convert = [&](const std::string& file, const std::string& kind, const std::string& name) {
    const std::string out = path(name);
    const CommandResult run = run_nec("augment " + file + " --kind " + kind + " --seed 4 -o " + out);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    return out;
  };
  const std::vector<std::string> sources = {authored_source, convert(authored_source, "axes", "src_axes.bvh"),
                                            convert(authored_source, "axes-random", "src_random.bvh")};
  const std::string target_axes = convert(authored_target, "axes", "dst_axes.bvh");
  // The conversion changed the local rotations and offsets, not the motion.
  const Clip source_clip = read_bvh(authored_source);
  const Clip source_axes = read_bvh(sources[1]);
  EXPECT_GT((source_axes.skeleton.offsets[1] - source_clip.skeleton.offsets[1]).norm(), 1e-3);
  const auto positions = [](const Clip& clip) { return forward_kinematics(clip.skeleton, clip.motion).positions; };
  const auto largest_distance = [](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    EXPECT_EQ(a.size(), b.size());
    double largest = 0.0;
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) largest = std::max(largest, (a[i] - b[i]).norm());
    return largest;
  };
  const double source_diameter = source_clip.skeleton.diameter();
  EXPECT_LT(largest_distance(positions(source_clip), positions(source_axes)), 1e-4 * source_diameter);

  std::vector<std::vector<int32_t>> codes;
  std::vector<std::vector<Vec3>> transferred;
  for (size_t i = 0; i < sources.size(); ++i) {
    const std::string tokens = path("convention" + std::to_string(i) + ".tokens.json");
    const CommandResult encode = run_nec("encode " + sources[i] + " --model " + shared("tat") + " -o " + tokens +
                                         " --threads 1");
    ASSERT_EQ(encode.exit_code, 0) << encode.output;
    codes.push_back(tat::read_tokens(tokens).codes);
    const std::string out = path("convention" + std::to_string(i) + "_dog.bvh");
    const CommandResult transfer = run_nec("transfer " + sources[i] + " --to " + authored_target + " --model " +
                                           shared("tat") + " -o " + out + " --threads 1");
    ASSERT_EQ(transfer.exit_code, 0) << transfer.output;
    transferred.push_back(positions(read_bvh(out)));
  }
  const Clip target_clip = read_bvh(authored_target);
  const double target_diameter = target_clip.skeleton.diameter();
  for (size_t i = 1; i < sources.size(); ++i) {
    EXPECT_EQ(codes[i], codes[0]) << sources[i];
    EXPECT_LT(largest_distance(transferred[i], transferred[0]), 1e-3 * target_diameter) << sources[i];
  }

  // Onto the target in the +X convention: the same motion, written in that file's own offsets.
  const std::string onto_axes = path("onto_axes.bvh");
  const CommandResult transfer = run_nec("transfer " + authored_source + " --to " + target_axes + " --model " +
                                         shared("tat") + " -o " + onto_axes + " --threads 1");
  ASSERT_EQ(transfer.exit_code, 0) << transfer.output;
  const Clip written = read_bvh(onto_axes);
  const Clip target_in_axes = read_bvh(target_axes);
  ASSERT_EQ(written.skeleton.joint_count(), target_in_axes.skeleton.joint_count());
  for (int j = 1; j < written.skeleton.joint_count(); ++j) {
    EXPECT_LT((written.skeleton.offsets[j] - target_in_axes.skeleton.offsets[j]).norm(), 1e-4 * target_diameter) << j;
  }
  EXPECT_LT(largest_distance(positions(written), transferred[0]), 1e-3 * target_diameter);
}

TEST_F(CliTat, LongClipsAreEncodedInWindows) {
  // A 2 s clip is 60 frames: with 16-frame windows and overlap 8 that is 7 windows.
  const std::string source = zoo_clip("c002");
  const std::string tokens = path("long.tokens.json");
  const CommandResult encode = run_nec("encode " + source + " --model " + shared("tat") + " -o " + tokens +
                                       " --window-overlap 8 --threads 1");
  ASSERT_EQ(encode.exit_code, 0) << encode.output;
  EXPECT_EQ(tat::read_tokens(tokens).steps(), 15);
  const CommandResult bad_overlap = run_nec("encode " + source + " --model " + shared("tat") + " -o " + tokens +
                                            " --window-overlap 6");
  EXPECT_EQ(bad_overlap.exit_code, 2) << bad_overlap.output;
}

TEST_F(CliTat, EvalReconWritesATablePerDataset) {
  const std::string json_path = path("recon.json");
  const CommandResult run = run_nec("eval recon --data " + shared("cache") + " --models " + shared("tat") + " --json " +
                                    json_path + " --threads 1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(contains(run.output, "| held |")) << run.output;
  const nlohmann::json results = nlohmann::json::parse(read_file(json_path))["results"];
  ASSERT_GE(results.size(), 2u);
  for (const auto& row : results) {
    EXPECT_GT(row["clips"].get<int>(), 0);
    EXPECT_GT(row["mpjpe"].get<double>(), 0.0);  // an untrained-for-long model is not exact
    EXPECT_LT(row["mpjpe"].get<double>(), 50.0);
    EXPECT_GT(row["geodesic_degrees"].get<double>(), 0.0);
    EXPECT_LE(row["geodesic_degrees"].get<double>(), 180.0);
    // The decoded joints turn (a briefly trained model is not a statue), and the table prints the JSON's value.
    const double turning = row["pose_turn_kept"].get<double>();
    EXPECT_GT(turning, 0.01);
    EXPECT_LT(turning, 3.0);
    EXPECT_TRUE(contains(run.output, fmt::format(" | {:.2f} | {:.2f} | ", row["geodesic_degrees"].get<double>(), turning)))
        << turning << "\n" << run.output;
  }
}

TEST_F(CliTat, BadInputNamesTheFileAndWritesNothing) {
  const std::string source = zoo_clip("c000_biped");
  // Missing model.
  CommandResult run = run_nec("encode " + source + " --model " + path("nowhere") + " -o " + path("t.json"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_TRUE(contains(run.output, "nowhere")) << run.output;
  EXPECT_FALSE(fs::exists(path("t.json")));
  // A model directory of another kind.
  run = run_nec("encode " + source + " --model " + shared("owo") + " -o " + path("t.json"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_TRUE(contains(run.output, "not a TAT checkpoint")) << run.output;
  // Malformed BVH: file and line.
  const std::string broken = dir_.write("broken.bvh", "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 zz\n}\n");
  run = run_nec("encode " + broken + " --model " + shared("tat") + " -o " + path("t.json"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_TRUE(contains(run.output, "broken.bvh:4")) << run.output;
  EXPECT_FALSE(fs::exists(path("t.json")));
  // Token file with a code outside the codebook.
  ASSERT_EQ(run_nec("encode " + source + " --model " + shared("tat") + " -o " + path("good.json")).exit_code, 0);
  std::string text = read_file(path("good.json"));
  const size_t at = text.find("\"tokens\": [\n  [") + 15;
  text.replace(at, text.find(',', at) - at, "999");
  write_file_atomic(path("bad.json"), text);
  run = run_nec("decode " + path("bad.json") + " --skeleton " + source + " --model " + shared("tat") + " -o " +
                path("out.bvh"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_TRUE(contains(run.output, "bad.json")) << run.output;
  EXPECT_TRUE(contains(run.output, "999")) << run.output;
  EXPECT_FALSE(fs::exists(path("out.bvh")));
  // Not a token file at all.
  run = run_nec("decode " + source + " --skeleton " + source + " --model " + shared("tat") + " -o " + path("out.bvh"));
  EXPECT_EQ(run.exit_code, 1) << run.output;
  EXPECT_FALSE(fs::exists(path("out.bvh")));
}

}  // namespace
}  // namespace nec

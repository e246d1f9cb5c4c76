// The `nec` binary: exit codes, error messages and outputs of the subcommands.
#include "nec/motion/bvh.h"
#include "nec/motion/files.h"
#include "nec/motion/kinematics.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace nec {
namespace {

namespace fs = std::filesystem;

using testing::CommandResult;
using testing::contains;
using testing::run_nec;

class Cli : public ::testing::Test {
 protected:
  std::string path(const std::string& name) const { return dir_ / name; }
  std::string write(const std::string& name, const std::string& text) const { return dir_.write(name, text); }
  testing::TempDir dir_;
};

const std::string kCmu = testing::cmu_bvh_dir() + "/01_01.bvh";

TEST_F(Cli, HelpShowsDefaultsAndUsageErrorsExitTwo) {
  const CommandResult help = run_nec("normalize --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("(default: 30)"), std::string::npos) << help.output;
  EXPECT_EQ(run_nec("").exit_code, 2);
  EXPECT_EQ(run_nec("frobnicate").exit_code, 2);
  EXPECT_EQ(run_nec("convert " + kCmu).exit_code, 2);  // missing -o
  EXPECT_EQ(run_nec("convert " + kCmu + " -o x.bvh --order QQQ").exit_code, 2);
  EXPECT_EQ(run_nec("augment " + kCmu + " -o x.bvh --kind nope").exit_code, 2);
  EXPECT_EQ(run_nec("augment " + kCmu + " -o x.bvh --seed abc").exit_code, 2);
}

TEST_F(Cli, InfoDescribesTheFile) {
  const CommandResult run = run_nec("info " + kCmu);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("joints    31"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("2752 at 120 fps"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("Zrotation Yrotation Xrotation"), std::string::npos);
  EXPECT_NE(run.output.find("LeftUpLeg"), std::string::npos);
  const CommandResult json = run_nec("info --json " + kCmu);
  ASSERT_EQ(json.exit_code, 0) << json.output;
  EXPECT_NE(json.output.find("{\"joints\": 31, \"end_sites\": 7, \"frames\": 2752, \"fps\": 120.0"), std::string::npos)
      << json.output;
}

TEST_F(Cli, BadInputExitsOneWithFileAndLineAndWritesNothing) {
  const std::string bad = write("bad.bvh", "HIERARCHY\nROOT A\n{\n  OFFSET 0 0 0\n  CHANNELS 1 Qrotation\n}\n");
  const std::string out = path("out.bvh");
  for (const std::string& command : {"info " + bad, "convert " + bad + " -o " + out, "normalize " + bad + " -o " + out,
                                     "augment " + bad + " -o " + out}) {
    const CommandResult run = run_nec(command);
    EXPECT_EQ(run.exit_code, 1) << command << "\n" << run.output;
    EXPECT_NE(run.output.find("bad.bvh:5: unknown channel 'Qrotation'"), std::string::npos) << run.output;
  }
  EXPECT_EQ(run_nec("info " + path("missing.bvh")).exit_code, 1);
  EXPECT_EQ(run_nec("info " + write("empty.bvh", "")).exit_code, 1);
  EXPECT_FALSE(fs::exists(out));
  // Nothing but the two inputs: no temporary files left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_.path()), fs::directory_iterator()), 2);
}

TEST_F(Cli, ConvertRoundTripsAndChangesOrder) {
  const std::string out = path("zyx.bvh");
  const CommandResult run = run_nec("convert " + kCmu + " -o " + out + " --order XYZ");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const Clip a = read_bvh(kCmu);
  const Clip b = read_bvh(out);
  EXPECT_EQ(b.skeleton.channels[1].euler_order(), EulerOrder::XYZ);
  const Pose pa = forward_kinematics(a.skeleton, a.motion);
  const Pose pb = forward_kinematics(b.skeleton, b.motion);
  EXPECT_LT(testing::max_position_difference(pa.positions, pb.positions), 1e-4);
}

TEST_F(Cli, NormalizeAndAugmentWriteReadableFiles) {
  const std::string normalized = path("n.bvh");
  const CommandResult run = run_nec("normalize " + kCmu + " -o " + normalized);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("resampled 120 -> 30 fps"), std::string::npos) << run.output;
  const Clip n = read_bvh(normalized);
  EXPECT_NEAR(n.skeleton.diameter(), 1.0, 1e-6);
  for (const std::string kind : {"rest", "length", "joints", "remove", "subdivide"}) {
    const std::string out = path(kind + ".bvh");
    const CommandResult augmented = run_nec("augment " + normalized + " --kind " + kind + " --seed 4 -o " + out);
    ASSERT_EQ(augmented.exit_code, 0) << kind << ": " << augmented.output;
    EXPECT_EQ(read_bvh(out).motion.frame_count, n.motion.frame_count);
  }
}

// `nec eval transfer` measures each file in its own body sizes: the CMU clip and
// its normalized copy (another unit, scale and frame rate) travel alike.
TEST_F(Cli, EvalTransferComparesPairsInBodySizes) {
  const std::string normalized = path("n.bvh");
  ASSERT_EQ(run_nec("normalize " + kCmu + " -o " + normalized).exit_code, 0);
  const std::string json_path = path("check.json");
  const CommandResult run = run_nec("eval transfer " + kCmu + " " + normalized + " --json " + json_path);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("| speed src / out (sizes/s) | ratio |"), std::string::npos) << run.output;
  const nlohmann::json check = nlohmann::json::parse(read_file(json_path)).at(0);
  EXPECT_NEAR(check["speed_ratio"].get<double>(), 1.0, 0.02) << check.dump(1);
  EXPECT_NEAR(check["heading_difference_deg"].get<double>(), 0.0, 1.0);
  EXPECT_LT(check["output_measurements"]["bone_length_change"].get<double>(), 1e-3);
  EXPECT_GT(check["source_measurements"]["speed"].get<double>(), 0.1);
  // Another unit: the two files are not in one frame, so their joints are not compared.
  EXPECT_TRUE(check["joint_distance"].is_null()) << check.dump(1);
  // The clip against itself is in one frame: its joints are where they are.
  const CommandResult itself = run_nec("eval transfer " + kCmu + " " + kCmu + " --json " + json_path);
  ASSERT_EQ(itself.exit_code, 0) << itself.output;
  EXPECT_NEAR(nlohmann::json::parse(read_file(json_path)).at(0)["joint_distance"].get<double>(), 0.0, 1e-12);

  const CommandResult odd = run_nec("eval transfer " + kCmu);
  EXPECT_EQ(odd.exit_code, 2);
  EXPECT_NE(odd.output.find("give pairs"), std::string::npos) << odd.output;
  const std::string unwritten = path("never.json");
  const CommandResult missing = run_nec("eval transfer " + kCmu + " " + path("gone.bvh") + " --json " + unwritten);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("gone.bvh"), std::string::npos) << missing.output;
  EXPECT_FALSE(fs::exists(unwritten));
}

TEST_F(Cli, ViewWritesAStripAndRejectsBadArguments) {
  const std::string strip = path("strip.png");
  const CommandResult run = run_nec("view --frames 3 --height 120 " + kCmu + " -o " + strip);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string png = read_file(strip);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(run_nec("view --frames 3 " + kCmu + " -o " + path("strip.html")).exit_code, 2);  // a strip must be .png
  EXPECT_EQ(run_nec("view --frames 3 " + path("missing.bvh") + " -o " + path("x.png")).exit_code, 1);
  EXPECT_FALSE(fs::exists(path("x.png")));
}

// Rigged assets through the commands: described, converted to BVH and back onto the asset, prepared
// with BVH files, and the outputs nec cannot write refused with nothing written.
TEST_F(Cli, ZooListsPlansAndActionsAndDrawsOnlyTheAskedOnes) {
  const CommandResult help = run_nec("zoo --help");
  ASSERT_EQ(help.exit_code, 0);
  EXPECT_TRUE(contains(help.output, "biped")) << help.output;
  EXPECT_TRUE(contains(help.output, "wave raise_hands point clap bow crouch kick")) << help.output;
  const CommandResult made = run_nec("zoo --out " + path("z") + " --plans biped --actions wave,kick --creatures 2 "
                                     "--clips-per-creature 4 --seconds 1 --quiet");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  int clips = 0;
  for (const auto& entry : fs::recursive_directory_iterator(path("z"))) {
    if (entry.path().extension() != ".bvh") continue;
    ++clips;
    const std::string name = entry.path().stem().string();
    EXPECT_TRUE(contains(name, "_wave") || contains(name, "_kick")) << name;
  }
  EXPECT_EQ(clips, 8);
  // Another zoo is not written over this one (their clips would mix) unless --force replaces it.
  const std::string again = "zoo --out " + path("z") + " --plans quadruped --creatures 1 --clips-per-creature 1 --quiet";
  const CommandResult refused = run_nec(again);
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_TRUE(contains(refused.output, "is not empty; pass --force to replace it")) << refused.output;
  const CommandResult replaced = run_nec(again + " --force");
  ASSERT_EQ(replaced.exit_code, 0) << replaced.output;
  int left = 0, quadrupeds = 0;
  for (const auto& entry : fs::recursive_directory_iterator(path("z"))) {
    if (entry.path().extension() != ".bvh") continue;
    ++left;
    quadrupeds += contains(entry.path().stem().string(), "quadruped");
  }
  EXPECT_EQ(left, 1) << "only the new zoo's clip";
  EXPECT_EQ(quadrupeds, 1);
  const CommandResult unknown = run_nec("zoo --out " + path("u") + " --actions moonwalk");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_TRUE(contains(unknown.output, "unknown action 'moonwalk'")) << unknown.output;
  const CommandResult none = run_nec("zoo --out " + path("n") + " --plans fish --actions wave");
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_TRUE(contains(none.output, "a fish supports none of the actions")) << none.output;
  EXPECT_FALSE(fs::exists(path("u")) || fs::exists(path("n")));
}

TEST_F(Cli, PrepareCaptionsClipsFromTakeDescriptionsFoundBelowTheTable) {
  if (!fs::exists(kCmu)) GTEST_SKIP() << "assimp-testmodels is not installed";
  fs::create_directories(path("cmu/bvh"));
  fs::copy_file(kCmu, path("cmu/bvh/01_01.bvh"));
  // As CMU's own table: a third column, rows naming takes kept in bvh/, one take that is not there.
  const std::string csv = write("cmu/descriptions.csv", "file,description,subject\n"
                                                        "01_01.bvh,\"playground - forward jumps, turn around\",1\n"
                                                        "99_01.bvh,walk,99\n");
  const CommandResult run = run_nec("prepare cmu=" + path("cmu/bvh") + " --descriptions " + csv +
                                    " --creature cmu=person -o " + path("cache"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(contains(run.output, "names 1 of its 2 files that do not exist")) << run.output;
  EXPECT_TRUE(contains(run.output, "captioned from its description")) << run.output;
  const nlohmann::json manifest = nlohmann::json::parse(read_file(path("cache/manifest.json")));
  int described = 0;
  for (const auto& clip : manifest["clips"]) {
    described += clip["captions"][0].get<std::string>().find("jumps forward") != std::string::npos;
  }
  EXPECT_GT(described, 0);
}

TEST_F(Cli, PrepareFlagsAnImplausibleFrameTimeAndTakesTheTrueRate) {
  if (!fs::exists(kCmu)) GTEST_SKIP() << "assimp-testmodels is not installed";
  // 01_01's first two seconds of 120-fps capture, written as if each frame lasted a second.
  Clip clip = read_bvh(kCmu);
  clip.motion = clip.motion.slice(0, 240);
  clip.motion.fps = 1.0;
  fs::create_directories(path("slow"));
  write_bvh(path("slow/slow.bvh"), clip.skeleton, clip.motion);
  const CommandResult flagged = run_nec("prepare " + path("slow") + " -o " + path("slow_cache"));
  ASSERT_EQ(flagged.exit_code, 0) << flagged.output;
  EXPECT_TRUE(contains(flagged.output, "a Frame Time of")) << flagged.output;
  const CommandResult given = run_nec("prepare " + path("slow") + " -o " + path("given_cache") + " --source-fps 120");
  ASSERT_EQ(given.exit_code, 0) << given.output;
  EXPECT_FALSE(contains(given.output, "Frame Time")) << given.output;
  EXPECT_TRUE(contains(given.output, "resampled 120 -> 30 fps")) << given.output;
  const CommandResult negative = run_nec("prepare " + path("slow") + " -o " + path("bad_cache") + " --source-fps -1");
  EXPECT_EQ(negative.exit_code, 2) << negative.output;
  EXPECT_FALSE(fs::exists(path("bad_cache")));
}

TEST_F(Cli, AssetsInAndOutThroughTheCommands) {
  const std::string wuson = "/usr/share/assimp/models/X/Testwuson.X";
  if (!fs::exists(wuson)) GTEST_SKIP() << "assimp-testmodels is not installed";
  const CommandResult info = run_nec("info --no-tree " + wuson);
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_TRUE(contains(info.output, "animation 'Wuson_Walk': 109 frames at 30 fps")) << info.output;
  EXPECT_TRUE(contains(info.output, "(longest root-to-leaf chain, metres)")) << info.output;

  const std::string walk = path("walk.bvh"), animated = path("walk.glb");
  ASSERT_EQ(run_nec("convert " + wuson + "#Wuson_Walk -o " + walk).exit_code, 0);
  const CommandResult onto = run_nec("convert " + walk + " --onto " + wuson + " -o " + animated);
  ASSERT_EQ(onto.exit_code, 0) << onto.output;
  const CommandResult back = run_nec("info --no-tree " + animated);
  EXPECT_TRUE(contains(back.output, "animation 'walk': 109 frames")) << back.output;  // first, named after the BVH

  fs::create_directories(path("mixed"));
  fs::copy_file(wuson, path("mixed/wuson.x"));
  fs::copy_file(kCmu, path("mixed/01_01.bvh"));
  const CommandResult prepared = run_nec("prepare " + path("mixed") + " -o " + path("cache") + " --quiet");
  ASSERT_EQ(prepared.exit_code, 0) << prepared.output;

  // Refused before any work, nothing written: FBX output, GLB onto a BVH, GLB without --onto, another skeleton.
  for (const std::string& command :
       {"convert " + walk + " --onto " + wuson + " -o " + path("out.fbx"),
        "convert " + walk + " --onto " + kCmu + " -o " + path("out.glb"),
        "convert " + kCmu + " --onto " + wuson + " -o " + path("out.glb")}) {
    const CommandResult run = run_nec(command);
    EXPECT_EQ(run.exit_code, 1) << command << "\n" << run.output;
  }
  EXPECT_EQ(run_nec("convert " + walk + " -o " + path("out.glb")).exit_code, 2);
  EXPECT_FALSE(fs::exists(path("out.fbx")));
  EXPECT_FALSE(fs::exists(path("out.glb")));
}

TEST_F(Cli, DemoWritesCacheBvhStripsAndPages) {
  const CommandResult run = run_nec("demo --creatures 3 --clips-per-creature 2 --out " + path("demo"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const std::string row : {"| biped | ", "| quadruped | ", "| hexapod | ", "| cmu (real) | "}) {
    EXPECT_NE(run.output.find(row), std::string::npos) << row << "\n" << run.output;
  }
  EXPECT_TRUE(fs::exists(path("demo/cache/manifest.json")));
  int strips = 0;
  for (const auto& entry : fs::directory_iterator(path("demo/strips"))) strips += entry.path().extension() == ".png";
  EXPECT_EQ(strips, 4);  // three zoo creatures and one CMU clip
  // Every written BVH reads back.
  int bvh = 0;
  for (const auto& entry : fs::directory_iterator(path("demo/bvh"))) {
    EXPECT_NO_THROW(read_bvh(entry.path().string())) << entry.path();
    ++bvh;
  }
  EXPECT_EQ(bvh, 4 * 5);  // normalized + four augmentations each
  // One page links everything; with the default models (and word vectors) it shows their three uses too.
  EXPECT_TRUE(contains(read_file(path("demo/index.html")), "clips.html"));
  if (contains(run.output, "default models:")) {
    for (const std::string page : {"transfers", "generated", "retrieved"}) {
      EXPECT_TRUE(fs::exists(path("demo/models/" + page + ".html"))) << page;
      EXPECT_TRUE(fs::exists(path("demo/models/" + page + ".png"))) << page;
      EXPECT_TRUE(contains(read_file(path("demo/index.html")), "models/" + page + ".html")) << page;
    }
    for (int i = 1; i <= 3; ++i) EXPECT_NO_THROW(read_bvh(path("demo/models/generated_" + std::to_string(i) + ".bvh")));
    // The diffusion model's 4-s motion beside the GPT's, on the same skeleton, for each of the three plans.
    EXPECT_TRUE(contains(run.output, "(3 by diffusion)")) << run.output;
    for (int i = 1; i <= 3; ++i) {
      const std::string stem = "demo/models/generated_" + std::to_string(i);
      const Clip diffused = read_bvh(path(stem + "_diffusion.bvh"));
      EXPECT_EQ(diffused.motion.frame_count, 120) << i;
      EXPECT_EQ(diffused.skeleton.joint_count(), read_bvh(path(stem + ".bvh")).skeleton.joint_count()) << i;
    }
    // Two captions of 3 s each (22 token steps of 4 frames at 30 fps) make one motion of both.
    EXPECT_EQ(read_bvh(path("demo/models/generated_two_captions.bvh")).motion.frame_count, 2 * 22 * 4);
    EXPECT_TRUE(contains(read_file(path("demo/models/generated.html")), "3-6 s: a person turns to the left"));
  } else {
    EXPECT_TRUE(contains(run.output, "no default models")) << run.output;
  }
}

}  // namespace
}  // namespace nec

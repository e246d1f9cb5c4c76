// The zoo writer: layout, sidecar captions, manifest, held-out plans, plan
// rotation, byte-for-byte determinism, and reading it back with the corpus
// loader that `nec prepare` uses.
#include "nec/motion/bvh.h"
#include "nec/corpus/captions.h"
#include "nec/corpus/corpus.h"
#include "nec/motion/files.h"
#include "nec/zoo/zoo.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <filesystem>
#include <map>

namespace nec::zoo {
namespace {

namespace fs = std::filesystem;

class Zoo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("nec_zoo_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  ZooOptions small(const std::string& sub) const {
    ZooOptions options;
    options.out_dir = (dir_ / sub).string();
    options.creatures = 9;
    options.clips_per_creature = 2;
    options.seed = 5;
    options.seconds = 2.0;
    return options;
  }

  fs::path dir_;
};

TEST_F(Zoo, WritesClipsSidecarsAndManifest) {
  ZooOptions options = small("a");
  options.held_out_plans = {BodyPlan::Spider, BodyPlan::Dragon};
  const ZooSummary summary = write_zoo(options);
  ASSERT_EQ(summary.clips.size(), 18u);
  EXPECT_EQ(summary.creatures, 9);
  EXPECT_EQ(summary.held_out_creatures, 2);
  for (const ZooClip& clip : summary.clips) {
    const fs::path bvh = fs::path(options.out_dir) / clip.bvh_file;
    const fs::path txt = fs::path(options.out_dir) / clip.captions_file;
    ASSERT_TRUE(fs::exists(bvh)) << bvh;
    EXPECT_EQ(txt.stem(), bvh.stem());
    EXPECT_EQ(clip.plan, kAllBodyPlans[clip.creature_index % std::size(kAllBodyPlans)]) << "creature i has plan i mod the plan count";
    const bool held = clip.plan == BodyPlan::Spider || clip.plan == BodyPlan::Dragon;
    EXPECT_EQ(clip.held_out, held);
    EXPECT_EQ(clip.bvh_file.rfind(held ? "held_out/" : "seen/", 0), 0u) << clip.bvh_file;
    EXPECT_GE(clip.joint_count, 7);
    EXPECT_LE(clip.joint_count, 140);
    // The sidecar is what `nec prepare` reads: the three captions, one per line.
    EXPECT_EQ(captions_for(bvh.string()), clip.captions.lines());
    const Clip read = read_bvh(bvh.string());
    EXPECT_EQ(read.skeleton.joint_count(), clip.joint_count);
    EXPECT_EQ(read.motion.frame_count, clip.frames);
    EXPECT_EQ(clip.frames, 60);
  }
  for (const auto& entry : fs::recursive_directory_iterator(options.out_dir)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << "left behind: " << entry.path();
  }

  const nlohmann::json manifest = nlohmann::json::parse(read_file(summary.manifest_path));
  EXPECT_EQ(manifest["format"], "nec-zoo");
  EXPECT_EQ(manifest["version"], 1);
  ASSERT_EQ(manifest["clips"].size(), 18u);
  EXPECT_EQ(manifest["held_out_plans"], nlohmann::json({"spider", "dragon"}));
  for (size_t i = 0; i < summary.clips.size(); ++i) {
    const nlohmann::json& j = manifest["clips"][i];
    const ZooClip& clip = summary.clips[i];
    EXPECT_EQ(j["file"], clip.bvh_file);
    EXPECT_EQ(j["creature"]["plan"], std::string(body_plan_name(clip.plan)));
    EXPECT_EQ(j["creature"]["species"], clip.species);
    EXPECT_EQ(j["creature"]["joints"], clip.joint_count);
    EXPECT_EQ(j["creature"]["seed"].get<uint64_t>(), clip.creature_seed);
    EXPECT_EQ(j["action"], std::string(action_name(clip.spec.action)));
    EXPECT_DOUBLE_EQ(j["parameters"]["speed_body_lengths_per_second"].get<double>(), clip.spec.speed);
    EXPECT_DOUBLE_EQ(j["parameters"]["turn_rate_degrees_per_second"].get<double>(), clip.spec.turn_rate);
    EXPECT_EQ(j["captions"]["long"], clip.captions.long_text);
  }
}

TEST_F(Zoo, SameSeedSameBytesOtherSeedOtherZoo) {
  const ZooSummary a = write_zoo(small("a"));
  const ZooSummary b = write_zoo(small("b"));
  ZooOptions other = small("c");
  other.seed = 6;
  const ZooSummary c = write_zoo(other);
  ASSERT_EQ(a.clips.size(), b.clips.size());
  int differing = 0;
  for (size_t i = 0; i < a.clips.size(); ++i) {
    const std::string bvh_a = read_file((dir_ / "a" / a.clips[i].bvh_file).string());
    EXPECT_EQ(bvh_a, read_file((dir_ / "b" / b.clips[i].bvh_file).string())) << a.clips[i].bvh_file;
    EXPECT_EQ(read_file((dir_ / "a" / a.clips[i].captions_file).string()),
              read_file((dir_ / "b" / b.clips[i].captions_file).string()));
    differing += bvh_a != read_file((dir_ / "c" / c.clips[i].bvh_file).string());
  }
  EXPECT_EQ(read_file(a.manifest_path), read_file(b.manifest_path));
  EXPECT_EQ(differing, static_cast<int>(a.clips.size())) << "another seed must give other creatures and clips";
}

TEST_F(Zoo, CorpusLoaderReadsTheZooWithItsCaptions) {
  ZooOptions options = small("zoo");
  options.held_out_plans = {BodyPlan::Snake};
  const ZooSummary summary = write_zoo(options);
  std::map<std::string, std::vector<std::string>> captions_of;  // file name -> captions
  int seen = 0;
  for (const ZooClip& clip : summary.clips) {
    if (clip.held_out) continue;
    ++seen;
    captions_of[fs::path(clip.bvh_file).filename().string()] = clip.captions.lines();
  }
  const std::vector<CorpusFile> files = find_corpus_files({"zoo=" + (fs::path(options.out_dir) / "seen").string()});
  ASSERT_EQ(static_cast<int>(files.size()), seen) << "held-out plans must not be under seen/";
  CorpusOptions corpus;
  corpus.threads = 2;
  const CorpusResult result = load_corpus(files, corpus);
  ASSERT_EQ(result.files.size(), files.size());
  for (const CorpusFileResult& file : result.files) {
    EXPECT_TRUE(file.error.empty()) << file.path << ": " << file.error;
    EXPECT_EQ(file.clips, 1) << file.path;
    EXPECT_EQ(file.segments, 0) << file.path << ": captioned clips must not be cut";
  }
  ASSERT_EQ(static_cast<int>(result.entries.size()), seen);
  for (const CacheEntry& entry : result.entries) {
    EXPECT_TRUE(entry.prepared.report.accepted()) << entry.source << ": " << entry.prepared.report.rejection;
    const std::string name = fs::path(entry.source).filename().string();
    ASSERT_TRUE(captions_of.count(name)) << name;
    EXPECT_EQ(entry.captions, captions_of[name]) << name;
    EXPECT_EQ(entry.dataset, "zoo");
  }
  const std::vector<CorpusFile> held = find_corpus_files({(fs::path(options.out_dir) / "held_out").string()});
  EXPECT_EQ(held.size(), summary.clips.size() - static_cast<size_t>(seen));
}

TEST_F(Zoo, PlansOptionAndValidation) {
  ZooOptions options = small("p");
  options.plans = {BodyPlan::Snake, BodyPlan::Fish};
  options.creatures = 4;
  const ZooSummary summary = write_zoo(options);
  for (const ZooClip& clip : summary.clips) {
    EXPECT_EQ(clip.plan, clip.creature_index % 2 == 0 ? BodyPlan::Snake : BodyPlan::Fish);
  }
  ZooOptions bad = small("q");
  bad.plans = {BodyPlan::Fish};
  bad.held_out_plans = {BodyPlan::Spider};
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = small("q");
  bad.creatures = 0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = small("q");
  bad.out_dir.clear();
  EXPECT_THROW(write_zoo(bad), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir_ / "q"));
}

// Over many creatures every action of every plan gets picked, and the clip
// specs use the whole range of speeds and both turn directions.
TEST_F(Zoo, ClipSpecsCoverActionsSpeedsAndTurns) {
  ZooOptions options = small("unused");
  std::map<std::string, int> actions;
  int left = 0, right = 0, still_starts = 0;
  for (int i = 0; i < 150; ++i) {
    const Creature creature = make_creature(zoo_creature_plan(options, i), zoo_creature_seed(options, i));
    for (int k = 0; k < 12; ++k) {
      const MotionSpec spec = zoo_clip_spec(creature, options, k);
      EXPECT_TRUE(supports_action(creature.plan, spec.action));
      ++actions[std::string(body_plan_name(creature.plan)) + "/" + std::string(action_name(spec.action))];
      left += spec.turn_rate > 0;
      right += spec.turn_rate < 0;
      still_starts += spec.start_from_still;
    }
  }
  size_t supported = 0;
  for (BodyPlan plan : kAllBodyPlans) supported += supported_actions(plan).size();
  EXPECT_EQ(actions.size(), supported);
  for (BodyPlan plan : kAllBodyPlans) {
    for (Action action : supported_actions(plan)) {
      EXPECT_TRUE(actions.count(std::string(body_plan_name(plan)) + "/" + std::string(action_name(action))))
          << body_plan_name(plan) << " never " << action_name(action);
    }
  }
  EXPECT_GT(left, 10);
  EXPECT_GT(right, 10);
  EXPECT_GT(still_starts, 10);
}

}  // namespace
}  // namespace nec::zoo

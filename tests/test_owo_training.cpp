// OwO pretraining data and runs: skeleton sets split by body plan, rig
// augmentation, the training config file, the learning-rate schedule, and a
// trainer whose resumed steps equal the uninterrupted ones.
#include "nec/motion/error.h"
#include "nec/corpus/preprocess.h"
#include "nec/owo/graph.h"
#include "nec/owo/skeleton_set.h"
#include "nec/owo/training.h"
#include "nec/train/config_fields.h"
#include "nec/zoo/creature.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace nec {
namespace {

using owo::PretrainSkeleton;
using owo::SkeletonSet;

// Same reason as test_owo.cpp: small tensors, two test programs per two cores.
constexpr int kTorchThreads = 1;

// One clip per creature: `creatures` seeds of each plan, labelled like `nec zoo`
// writes them ("zoo/c003_spider/walk.bvh"), skeletons named "<plan>-<seed>".
DatasetCache zoo_cache(const std::vector<zoo::BodyPlan>& plans, int creatures, const std::string& dataset = "zoo",
                       const std::vector<std::string>& held_out_skeletons = {}) {
  std::vector<CacheEntry> entries;
  int index = 0;
  for (int seed = 0; seed < creatures; ++seed) {
    for (zoo::BodyPlan plan : plans) {
      const zoo::Creature creature = zoo::make_creature(plan, static_cast<uint64_t>(seed));
      Motion motion = Motion::rest(creature.skeleton, 6, 30.0);
      for (int t = 0; t < motion.frame_count; ++t) {
        for (int j = 1; j < motion.joint_count; ++j) {
          motion.rotation(t, j) = Quat(Eigen::AngleAxisd(0.3 * std::sin(t + j), Vec3::UnitX()));
        }
      }
      const std::string name = std::string(zoo::body_plan_name(plan)) + "-" + std::to_string(seed);
      const std::string source = dataset + "/c" + std::to_string(100 + index++) + "_" +
                                 std::string(zoo::body_plan_name(plan)) + "/walk.bvh";
      CacheEntry entry;
      entry.prepared = preprocess(Clip{creature.skeleton, motion, {}}, source);
      entry.source = source;
      entry.dataset = dataset;
      entry.captions = {"it walks"};
      entry.skeleton_name = name;
      entries.push_back(std::move(entry));
    }
  }
  CacheOptions options;
  options.split.held_out_skeletons = held_out_skeletons;
  return build_cache(entries, options);
}

std::set<std::string> hashes(const std::vector<PretrainSkeleton>& skeletons) {
  std::set<std::string> out;
  for (const PretrainSkeleton& s : skeletons) out.insert(s.hash);
  return out;
}

const std::vector<zoo::BodyPlan> kPlans = {zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped, zoo::BodyPlan::Spider,
                                           zoo::BodyPlan::Snake, zoo::BodyPlan::Fish};

TEST(OwoSkeletonSet, HoldsOutWholeBodyPlans) {
  const DatasetCache cache = zoo_cache(kPlans, 3, "zoo", {"quadruped-2"});
  const std::vector<PretrainSkeleton> all = owo::skeletons_from_cache(cache, 4, 1);
  ASSERT_EQ(all.size(), 15u);
  for (const PretrainSkeleton& s : all) {
    EXPECT_EQ(s.poses.frame_count, 4) << s.name;
    EXPECT_EQ(s.poses.joint_count, s.skeleton.joint_count()) << s.name;
    EXPECT_EQ(s.canonical_names.size(), static_cast<size_t>(s.skeleton.joint_count())) << s.name;
  }

  owo::HoldOut hold_out;
  hold_out.patterns = {"spider", "snake", "dragon"};
  const SkeletonSet set = owo::split_skeleton_set(all, hold_out);
  EXPECT_EQ(set.unmatched_patterns, std::vector<std::string>{"dragon"});
  ASSERT_EQ(set.held_out.size(), 7u);  // 3 spiders, 3 snakes, the quadruped the cache holds out
  ASSERT_EQ(set.train.size(), 8u);
  int spiders = 0, snakes = 0, cache_held = 0;
  for (const PretrainSkeleton& s : set.held_out) {
    if (s.group == "spider") {
      ++spiders;
      EXPECT_EQ(s.name.rfind("spider-", 0), 0u) << s.name;
    } else if (s.group == "snake") {
      ++snakes;
      EXPECT_EQ(s.name.rfind("snake-", 0), 0u) << s.name;
    } else if (s.group == "cache test split") {
      ++cache_held;
      EXPECT_EQ(s.name, "quadruped-2");
    }
  }
  EXPECT_EQ(spiders, 3);
  EXPECT_EQ(snakes, 3);
  EXPECT_EQ(cache_held, 1);
  for (const PretrainSkeleton& s : set.train) {
    EXPECT_EQ(s.group, "train");
    EXPECT_FALSE(owo::matches_hold_out(s, "spider") || owo::matches_hold_out(s, "snake")) << s.name;
    EXPECT_EQ(hashes(set.held_out).count(s.hash), 0u) << s.name;
  }

  // Without the cache's own hold-out the quadruped trains.
  hold_out.cache_held_out = false;
  EXPECT_EQ(owo::split_skeleton_set(all, hold_out).train.size(), 9u);
  // Names, datasets and path patterns.
  EXPECT_EQ(owo::split_skeleton_set(all, owo::HoldOut{{"fish-*"}, false}).held_out.size(), 3u);
  EXPECT_EQ(owo::split_skeleton_set(all, owo::HoldOut{{"zoo/c1??_biped/*"}, false}).held_out.size(), 3u);
  EXPECT_EQ(owo::split_skeleton_set(all, owo::HoldOut{{"zoo"}, false}).train.size(), 0u);
}

TEST(OwoSkeletonSet, ASkeletonHeldOutAnywhereNeverTrains) {
  // The same creatures in two caches; in the second they are one held-out dataset.
  const std::vector<zoo::BodyPlan> plans = {zoo::BodyPlan::Biped, zoo::BodyPlan::Bird};
  std::vector<PretrainSkeleton> all = owo::skeletons_from_cache(zoo_cache(plans, 2, "zoo"), 0, 1);
  for (PretrainSkeleton& s : owo::skeletons_from_cache(zoo_cache({zoo::BodyPlan::Bird}, 1, "heldbirds"), 0, 1)) {
    all.push_back(std::move(s));
  }
  const SkeletonSet set = owo::split_skeleton_set(all, owo::HoldOut{{"heldbirds"}, true});
  ASSERT_EQ(set.held_out.size(), 1u);  // bird-0, merged from both caches
  EXPECT_EQ(set.held_out[0].name, "bird-0");
  EXPECT_EQ(set.train.size(), 3u);
  EXPECT_EQ(hashes(set.train).count(set.held_out[0].hash), 0u);
  EXPECT_EQ(hashes(set.train).size() + hashes(set.held_out).size(), 4u);
}

TEST(OwoSkeletonSet, AugmentationYieldsValidSkeletons) {
  const std::vector<PretrainSkeleton> all = owo::skeletons_from_cache(zoo_cache(kPlans, 1), 6, 2);
  owo::AugmentOptions always;
  always.probability = always.rest_pose = always.bone_length = always.joint_removal = always.subdivision = 1.0;
  always.validate();
  owo::AugmentOptions remove_only = always, subdivide_only = always;
  remove_only.rest_pose = remove_only.bone_length = remove_only.subdivision = 0.0;
  subdivide_only.rest_pose = subdivide_only.bone_length = subdivide_only.joint_removal = 0.0;
  SplitMix64 rng(11);
  int changed_offsets = 0;
  for (const PretrainSkeleton& s : all) {
    const int joints = s.skeleton.joint_count();
    for (int draw = 0; draw < 20; ++draw) {
      const owo::AugmentedSkeleton rig = owo::augment_skeleton(s, always, rng);
      ASSERT_NO_THROW(rig.skeleton.validate()) << s.name;
      ASSERT_EQ(rig.canonical_names.size(), static_cast<size_t>(rig.skeleton.joint_count())) << s.name;
      EXPECT_EQ(rig.skeleton.parents[0], -1);
      EXPECT_GT(rig.skeleton.diameter(), 0.0) << s.name;
      const owo::SkeletonGraph graph = owo::make_skeleton_graph(rig.skeleton);
      EXPECT_TRUE(torch::isfinite(graph.edge_features).all().item<bool>()) << s.name;
      if (rig.skeleton.joint_count() == joints) {
        double largest = 0.0;
        for (int j = 0; j < joints; ++j) largest = std::max(largest, (rig.skeleton.offsets[j] - s.skeleton.offsets[j]).norm());
        changed_offsets += largest > 1e-6;
      }
      const owo::AugmentedSkeleton fewer = owo::augment_skeleton(s, remove_only, rng);
      EXPECT_LT(fewer.skeleton.joint_count(), joints) << s.name;
      EXPECT_NO_THROW(fewer.skeleton.validate()) << s.name;
      const owo::AugmentedSkeleton more = owo::augment_skeleton(s, subdivide_only, rng);
      EXPECT_GT(more.skeleton.joint_count(), joints) << s.name;
      ASSERT_EQ(more.canonical_names.size(), static_cast<size_t>(more.skeleton.joint_count())) << s.name;
      EXPECT_NO_THROW(more.skeleton.validate()) << s.name;
    }
  }
  EXPECT_GT(changed_offsets, 0);  // rest pose and bone lengths change the offsets

  owo::AugmentOptions never;
  never.probability = 0.0;
  const owo::AugmentedSkeleton same = owo::augment_skeleton(all[0], never, rng);
  EXPECT_EQ(same.skeleton.names, all[0].skeleton.names);
  EXPECT_EQ(same.canonical_names, all[0].canonical_names);

  owo::AugmentOptions bad;
  bad.rest_pose = 1.5;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

std::string input_error(const std::string& text) {
  try {
    owo::parse_owo_training_config(text, "cfg.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(OwoTrainingConfig, FieldsDefaultsErrorsAndRoundTrip) {
  const owo::OwoTrainingConfig defaults = owo::parse_owo_training_config("{}", "cfg.json");
  EXPECT_TRUE(defaults.names);
  EXPECT_EQ(defaults.encoder.name_dim, 100);

  EXPECT_NE(input_error(R"({"optimizer": {"learning_rate": "fast"}})").find("cfg.json: field 'optimizer.learning_rate' must be a number"),
            std::string::npos);
  EXPECT_NE(input_error(R"({"optimizer": {"lrr": 0.1}})").find("field 'optimizer.lrr' is not a known field"),
            std::string::npos);
  EXPECT_NE(input_error(R"({"batch_size": 2.5})").find("field 'batch_size' must be an integer"), std::string::npos);
  EXPECT_NE(input_error(R"({"data": {"held_out": "spider"}})").find("'data.held_out' must be a list of strings"),
            std::string::npos);
  EXPECT_NE(input_error(R"({"optimizer": {"learning_rate": -1}})").find("optimizer.learning_rate must be a positive number"),
            std::string::npos);
  EXPECT_NE(input_error(R"({"encoder": {"dim": 64, "heads": 5}})").find("encoder: OwoConfig: heads must divide dim"),
            std::string::npos);
  EXPECT_NE(input_error(R"({"names": false})").find("encoder.name_dim must be 0 when names is false"),
            std::string::npos);
  EXPECT_NE(input_error("{\"steps\": 10,}").find("cfg.json: not valid JSON"), std::string::npos);
  // A note for people is allowed in every object.
  EXPECT_EQ(input_error(R"({"comment": "CPU run", "optimizer": {"comment": "as the paper", "learning_rate": 1e-3}})"),
            "(no error)");

  owo::OwoTrainingConfig config;
  config.encoder.dim = 48;
  config.data.held_out = {"spider", "snake"};
  config.optimizer.learning_rate = 3e-4;
  config.seed = 77;
  const owo::OwoTrainingConfig back = owo::parse_owo_training_config(owo::owo_training_config_json(config), "x");
  EXPECT_TRUE(owo::differing_fields(config, back).empty());
  EXPECT_EQ(back.data.held_out, config.data.held_out);
  EXPECT_EQ(back.seed, 77u);

  owo::OwoTrainingConfig other = config;
  other.optimizer.learning_rate = 1e-3;
  other.steps = 99999;  // schedule fields may change on resume
  other.checkpoint_every = 7;
  other.data.held_out = {"spider"};
  EXPECT_EQ(owo::differing_fields(config, other), (std::vector<std::string>{"data.held_out", "optimizer.learning_rate"}));

  // The shipped configs parse.
  const std::filesystem::path configs = std::filesystem::path(__FILE__).parent_path().parent_path() / "configs";
  for (const char* name : {"owo_cpu.json", "owo_gpu.json"}) {
    const std::string path = (configs / name).string();
    EXPECT_NO_THROW(owo::read_owo_training_config(path)) << path;
  }
  EXPECT_EQ(train::fields_that_may_change<owo::OwoTrainingConfig>(),
            (std::set<std::string>{"steps", "log_every", "validate_every", "checkpoint_every"}));
}

owo::OwoTrainingConfig tiny_training_config() {
  owo::OwoTrainingConfig config;
  config.names = false;
  config.encoder.name_dim = 0;
  config.encoder.dim = 16;
  config.encoder.layers = 1;
  config.encoder.heads = 2;
  config.encoder.edge_dim = 8;
  config.pretrain.pairs_per_skeleton = 16;
  config.batch_size = 3;
  config.steps = 4;
  config.optimizer.warmup_steps = 2;
  config.data.held_out = {"snake"};
  return config;
}

TEST(OwoTrainer, ResumedStepsEqualTheUninterruptedRun) {
  torch::set_num_threads(kTorchThreads);
  const std::vector<zoo::BodyPlan> plans = {zoo::BodyPlan::Biped, zoo::BodyPlan::Fish, zoo::BodyPlan::Snake};
  const std::vector<PretrainSkeleton> all = owo::skeletons_from_cache(zoo_cache(plans, 2), 4, 1);
  const owo::OwoTrainingConfig config = tiny_training_config();
  auto make_set = [&] { return owo::split_skeleton_set(all, config.hold_out()); };
  testing::TempDir dir;
  const std::string checkpoint = dir / "owo";

  owo::OwoTrainer straight(config, make_set(), nullptr, torch::kCPU);
  std::vector<double> totals;
  for (int64_t step = 1; step <= 4; ++step) {
    totals.push_back(straight.step(step).total);
    if (step == 2) straight.save(checkpoint, step, {"zoo"});
  }
  for (double total : totals) EXPECT_TRUE(std::isfinite(total));

  owo::OwoTrainer resumed(config, make_set(), nullptr, torch::kCPU);
  ASSERT_EQ(resumed.resume(checkpoint), 2);
  for (int64_t step = 3; step <= 4; ++step) {
    const double total = resumed.step(step).total;
    const double tolerance = 1e-5 * std::max(1.0, std::abs(totals[step - 1]));
    EXPECT_NEAR(total, totals[step - 1], tolerance) << "step " << step;
    std::printf("step %lld: straight %.9g, resumed %.9g, diff %.3g\n", static_cast<long long>(step),
                totals[step - 1], total, std::abs(total - totals[step - 1]));
  }

  const std::optional<owo::OwoTrainingRecord> record = owo::read_owo_training_record(checkpoint);
  ASSERT_TRUE(record.has_value());
  EXPECT_EQ(record->step, 2);
  EXPECT_EQ(record->held_out_skeletons.size(), 2u);  // the snakes
  EXPECT_EQ(record->train_skeletons.size(), 4u);

  // Another learning rate: refused, naming the field.
  owo::OwoTrainingConfig changed = config;
  changed.optimizer.learning_rate = 0.5;
  owo::OwoTrainer other(changed, make_set(), nullptr, torch::kCPU);
  try {
    other.resume(checkpoint);
    FAIL() << "resumed with another config";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'optimizer.learning_rate' (checkpoint 0.001, now 0.5)"), std::string::npos) << e.what();
  }

  // Scores are fractions, and the skeletons held out are the snakes.
  const std::vector<owo::SkeletonScore> scores = resumed.score_held_out();
  ASSERT_EQ(scores.size(), 2u);
  for (const owo::SkeletonScore& s : scores) {
    EXPECT_EQ(s.group, "snake");
    EXPECT_EQ(s.pairs, static_cast<int64_t>(s.joints) * (s.joints - 1) / 2);
    EXPECT_GE(s.lca_accuracy(), 0.0);
    EXPECT_LE(s.lca_accuracy(), 1.0);
    EXPECT_TRUE(std::isfinite(s.offset_error));
    EXPECT_EQ(s.rebuilt, s.rebuild_failure.empty());
    EXPECT_GE(s.decoded_wrong_parents, 0);
    EXPECT_LE(s.decoded_wrong_parents, s.joints);
    EXPECT_EQ(s.decoded, s.decoded_wrong_parents == 0);
  }
}

}  // namespace
}  // namespace nec

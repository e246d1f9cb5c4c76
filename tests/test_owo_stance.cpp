// The stance network (owo/stance.h): examples drawn from a cache, a short training that learns a stance
// better than keeping the bind pose on rigs it never saw, and checkpoints that load what was saved.
#include "nec/corpus/preprocess.h"
#include "nec/corpus/rest_pose.h"
#include "nec/motion/error.h"
#include "nec/owo/graph.h"
#include "nec/owo/stance.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>

#include <unistd.h>

namespace nec {
namespace {

namespace fs = std::filesystem;

// Walks and idles of `creatures` seeds of each plan; the skeletons of seeds >= held_from are held out.
DatasetCache walking_zoo(const std::vector<zoo::BodyPlan>& plans, int creatures, int held_from) {
  std::vector<CacheEntry> entries;
  std::vector<std::string> held;
  for (int seed = 0; seed < creatures; ++seed) {
    for (zoo::BodyPlan plan : plans) {
      const zoo::Creature creature = zoo::make_creature(plan, static_cast<uint64_t>(seed));
      const std::string name = std::string(zoo::body_plan_name(plan)) + "-" + std::to_string(seed);
      if (seed >= held_from) held.push_back(name);
      for (zoo::Action action : {zoo::Action::Walk, zoo::Action::Idle}) {
        zoo::MotionSpec spec;
        spec.action = action;
        spec.seconds = 1.0;
        spec.speed = action == zoo::Action::Walk ? 0.5 * zoo::typical_speed(creature, action) : 0.0;
        CacheEntry entry;
        entry.source = "zoo/" + name + "/" + (action == zoo::Action::Walk ? "walk" : "idle") + ".bvh";
        entry.prepared = preprocess(Clip{creature.skeleton, zoo::synthesize_motion(creature, spec).motion, {}, ""},
                                    entry.source);
        entry.dataset = "zoo";
        entry.captions = {"it moves"};
        entry.skeleton_name = name;
        entries.push_back(std::move(entry));
      }
    }
  }
  CacheOptions options;
  options.split.held_out_skeletons = held;
  return build_cache(entries, options);
}

double median_of(const std::vector<owo::StanceScore>& scores) {
  for (const owo::StanceScore& s : scores) {
    if (s.group == "all") return s.median;
  }
  return -1.0;
}

TEST(OwoStance, ExamplesShowEachRigInSeveralPosesAgainstOneTruth) {
  torch::set_num_threads(1);
  const DatasetCache cache = walking_zoo({zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped}, 2, 1);
  owo::StanceExampleOptions options;
  options.frames_per_rig = 3;
  options.turned_per_rig = 2;
  options.rest_turned_per_rig = 2;
  const std::vector<owo::StanceExample> examples = owo::stance_examples(cache, options);
  ASSERT_EQ(examples.size(), 4u * (1 + 3 + 2 + 2));  // four rigs: file rest, frames, turned, rest turned
  std::map<std::string, int> held;
  for (const owo::StanceExample& e : examples) {
    held[e.rig] += e.held_out ? 1 : 0;
    EXPECT_EQ(e.bind.parents, e.stance.parents);
    EXPECT_EQ(e.canonical_names.size(), static_cast<size_t>(e.bind.joint_count()));
    EXPECT_NEAR(e.bind.diameter(), 1.0, 1e-6);
  }
  EXPECT_EQ(held["biped-0"], 0);
  EXPECT_EQ(held["biped-1"], 8);
  // The truth is the mean pose of the rig's clips: given it, the score is zero; the bind poses differ from it.
  class Truth : public StancePredictor {
   public:
    explicit Truth(const std::vector<owo::StanceExample>& all) {
      for (const owo::StanceExample& e : all) truths_[e.bind.joint_count()] = unit_bones(e.stance);
    }
    std::vector<Vec3> bone_directions(const Skeleton& bind, const std::vector<std::string>&) const override {
      return truths_.at(bind.joint_count());
    }

   private:
    std::map<int, std::vector<Vec3>> truths_;
  };
  std::vector<owo::StanceExample> bipeds;  // one joint count per rig for the lookup above
  for (const owo::StanceExample& e : examples) {
    if (e.rig == "biped-0") bipeds.push_back(e);
  }
  const auto by_pose = [](const owo::StanceExample& e) { return e.pose; };
  EXPECT_LT(median_of(owo::score_stance(Truth(bipeds), bipeds, by_pose)), 1e-3);
  EXPECT_GT(median_of(owo::score_stance(BindPoseStance(), bipeds, by_pose)), 2.0);

  // Length jitter gives the training rigs proportions of their own, the truth in the same proportions; held-out
  // rigs are scored as they are.
  options.length_jitter = 0.2;
  const std::vector<owo::StanceExample> jittered = owo::stance_examples(cache, options);
  ASSERT_EQ(jittered.size(), examples.size());
  const auto lengths = [](const Skeleton& s) {
    std::vector<double> out;
    for (int j = 1; j < s.joint_count(); ++j) out.push_back(s.offsets[j].norm());
    return out;
  };
  const auto spread_of_ratios = [](const std::vector<double>& a, const std::vector<double>& b) {
    double low = 1e9, high = 0.0;
    for (size_t j = 0; j < a.size(); ++j) {
      if (b[j] < 1e-9) continue;
      low = std::min(low, a[j] / b[j]);
      high = std::max(high, a[j] / b[j]);
    }
    return high / low - 1.0;
  };
  for (size_t i = 0; i < examples.size(); ++i) {
    const std::vector<double> before = lengths(examples[i].bind), after = lengths(jittered[i].bind);
    EXPECT_LT(spread_of_ratios(lengths(jittered[i].stance), after), 1e-6) << jittered[i].rig << " " << jittered[i].pose;
    if (jittered[i].held_out) {
      EXPECT_LT(spread_of_ratios(after, before), 1e-6) << jittered[i].rig;
    } else {
      EXPECT_GT(spread_of_ratios(after, before), 0.05) << jittered[i].rig;
    }
  }
}

TEST(OwoStance, ShortTrainingBeatsKeepingTheBindPoseOnUnseenRigs) {
  torch::set_num_threads(1);  // small batches: a second thread only adds synchronisation
  const DatasetCache cache = walking_zoo({zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped}, 4, 3);
  // Bind poses far from the stance (joints turned by up to 90 degrees), where keeping the bind pose is wrong.
  owo::StanceExampleOptions options;
  options.frames_per_rig = 2;
  options.turned_per_rig = 8;
  options.turned_fraction = 0.5;
  options.turned_degrees = 90.0;
  const std::vector<owo::StanceExample> examples = owo::stance_examples(cache, options);
  owo::StanceTrainingOptions training;
  training.steps = 200;
  training.batch_size = 8;
  training.passes = 2;  // from step 101 also the rigs as the network turned them
  owo::StanceNet net = owo::train_stance(examples, training, nullptr, {});

  const std::string dir = (fs::temp_directory_path() / ("nec_test_stance_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  owo::save_stance_checkpoint(dir, *net, {training.steps, 1, "test zoo", nlohmann::json::array()});
  const owo::NetworkStance stance = owo::NetworkStance::open(dir, "");
  EXPECT_EQ(stance.info().training_step, 200);

  std::vector<owo::StanceExample> unseen;
  for (const owo::StanceExample& e : examples) {
    if (e.held_out) unseen.push_back(e);
  }
  ASSERT_EQ(unseen.size(), 2u * (1 + 2 + 8 + options.rest_turned_per_rig));
  const auto all = [](const owo::StanceExample&) { return std::string("unseen"); };
  const double learned = median_of(owo::score_stance(stance, unseen, all));
  const double kept = median_of(owo::score_stance(BindPoseStance(), unseen, all));
  EXPECT_LT(learned, 0.75 * kept) << "learned " << learned << " degrees, bind pose kept " << kept;
  std::cout << "unseen rigs: learned " << learned << " degrees, bind pose kept " << kept << "\n";

  // What was saved is what loads: the same directions from the saved network and the trained one.
  const owo::StanceExample& e = unseen.front();
  const std::vector<Vec3> loaded = stance.bone_directions(e.bind, e.canonical_names);
  torch::NoGradGuard no_grad;
  const at::Tensor trained =
      net->forward(owo::collate({owo::make_skeleton_graph(e.bind, {}, net->encoder->config().graph)}, 0))[0];
  for (int j = 1; j < e.bind.joint_count(); ++j) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(loaded[j][k], trained[j][k].item<double>(), 1e-5);
  }

  // Two passes: the rig turned onto the first pass's directions, read again; the count travels in the checkpoint.
  owo::NetworkStance twice = owo::NetworkStance::open(dir, "");
  twice.set_passes(2);
  const Skeleton turned = reexpress_skeleton(e.bind, stance_frames(e.bind, loaded));
  const std::vector<Vec3> by_hand = stance.bone_directions(turned, e.canonical_names);
  const std::vector<Vec3> second = twice.bone_directions(e.bind, e.canonical_names);
  double moved = 0.0;
  for (int j = 1; j < e.bind.joint_count(); ++j) {
    EXPECT_LT((second[j] - by_hand[j]).norm(), 1e-6) << j;
    moved = std::max(moved, (second[j] - loaded[j]).norm());
  }
  EXPECT_GT(moved, 1e-4);  // the second pass changed something: it was run
  EXPECT_THROW(twice.set_passes(0), std::invalid_argument);
  owo::save_stance_checkpoint(dir, *net, {training.steps, 2, "test zoo", nlohmann::json::array()});
  EXPECT_EQ(owo::NetworkStance::open(dir, "").info().passes, 2);

  // A damaged checkpoint is refused with the file named.
  std::ofstream(fs::path(dir) / "config.json") << "{\"format\": \"nec-stance\", \"version\": 99}";
  try {
    owo::NetworkStance::open(dir, "");
    ADD_FAILURE() << "a damaged checkpoint loaded";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("config.json"), std::string::npos) << error.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace nec

// TatTrainer: a run saved and resumed takes the steps of one that never stopped, on a decaying learning rate;
// a resumed run with a later end goes on from the rate it had; configs that differ are refused.
#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/corpus/preprocess.h"
#include "nec/owo/pretrain.h"
#include "nec/tat/checkpoint.h"
#include "nec/tat/inference.h"
#include "nec/tat/training.h"
#include "nec/train/config_fields.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "tat_support.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

namespace nec {
namespace {

// Eight 2-s walks of zoo quadrupeds and bipeds, every clip in the train split.
DatasetCache walk_cache() {
  std::vector<CacheEntry> entries;
  for (int i = 0; i < 8; ++i) {
    const zoo::BodyPlan plan = i % 2 == 0 ? zoo::BodyPlan::Quadruped : zoo::BodyPlan::Biped;
    const zoo::Creature creature = zoo::make_creature(plan, 40 + static_cast<uint64_t>(i));
    zoo::MotionSpec spec;
    spec.action = zoo::Action::Walk;
    spec.seconds = 2.0;
    spec.seed = static_cast<uint64_t>(i);
    const std::string source = "zoo/c" + std::to_string(i) + "/walk.bvh";
    CacheEntry entry;
    entry.prepared = preprocess(Clip{creature.skeleton, zoo::synthesize_motion(creature, spec).motion, {}}, source);
    entry.source = source;
    entry.dataset = "zoo";
    entries.push_back(std::move(entry));
  }
  CacheOptions options;
  options.split.val_fraction = options.split.test_fraction = 0.0;
  return build_cache(entries, options);
}


tat::TatTrainConfig decaying_config() {
  tat::TatTrainConfig config;
  config.model.joint_embedding_dim = 16;
  config.model.dim = 16;
  config.model.heads = 2;
  config.model.quantizer.layers = 2;
  config.model.quantizer.codebook_size = 16;
  config.model.quantizer.code_dim = 16;
  config.optimizer.learning_rate = 3e-3;
  config.optimizer.warmup_steps = 2;
  config.optimizer.final_lr_fraction = 0.1;
  config.steps = 6;
  config.batch_size = 4;
  config.data.window_frames = 16;
  config.data.augment.probability = 0.5;
  config.seed = 9;
  return config;
}

TEST(TatTrainer, AResumedRunTakesTheStepsOfOneThatNeverStopped) {
  torch::set_num_threads(1);
  const DatasetCache cache = walk_cache();
  const tat::TatTrainConfig config = decaying_config();
  testing::TempDir dir;
  const std::string checkpoint = dir / "tat";

  tat::TatTrainer straight(config, cache, "walks", testing::tiny_frozen_owo(), nullptr, torch::kCPU);
  std::vector<tat::LossTerms> terms;
  for (int64_t step = 1; step <= 6; ++step) {
    terms.push_back(straight.step(step));
    if (step == 3) straight.save(checkpoint, step);
  }
  // The rate decays: every step after warm-up runs slower than the one before.
  for (int64_t step = 3; step <= 6; ++step) EXPECT_LT(terms[step - 1].at("lr"), terms[step - 2].at("lr")) << step;

  tat::TatTrainer resumed(config, cache, "walks", testing::tiny_frozen_owo(), nullptr, torch::kCPU);
  ASSERT_EQ(resumed.resume(checkpoint), 3);
  double largest = 0.0;
  for (int64_t step = 4; step <= 6; ++step) {
    const tat::LossTerms again = resumed.step(step);
    for (const char* key : {"loss", "rotation", "root", "position", "commitment", "lr"}) {
      const double difference = std::abs(again.at(key) - terms[step - 1].at(key));
      largest = std::max(largest, difference / std::max(1.0, std::abs(terms[step - 1].at(key))));
      EXPECT_LT(difference, 1e-6 * std::max(1.0, std::abs(terms[step - 1].at(key)))) << key << " at step " << step;
    }
  }
  double parameters = 0.0;
  auto resumed_tensors = resumed.tokenizer()->named_parameters();
  for (const auto& item : straight.tokenizer()->named_parameters()) {
    parameters = std::max(parameters, (item.value() - resumed_tensors[item.key()]).abs().max().item<double>());
  }
  std::printf("steps 4-6 resumed vs straight: largest relative term difference %.3g, parameter difference %.3g\n",
              largest, parameters);
  EXPECT_LT(parameters, 1e-6);
}

TEST(TatTrainer, ALaterEndGoesOnFromTheRateItHadAndOtherConfigsAreRefused) {
  torch::set_num_threads(1);
  const DatasetCache cache = walk_cache();
  const tat::TatTrainConfig config = decaying_config();
  testing::TempDir dir;
  const std::string checkpoint = dir / "tat";
  tat::TatTrainer first(config, cache, "walks", testing::tiny_frozen_owo(), nullptr, torch::kCPU);
  double rate_at_4 = 0.0;
  for (int64_t step = 1; step <= 4; ++step) rate_at_4 = first.step(step).at("lr");
  first.save(checkpoint, 4);

  tat::TatTrainConfig longer = config;
  longer.steps = 20;  // --resume --steps 20
  tat::TatTrainer resumed(longer, cache, "walks", testing::tiny_frozen_owo(), nullptr, torch::kCPU);
  ASSERT_EQ(resumed.resume(checkpoint), 4);
  const double rate_at_5 = resumed.step(5).at("lr");
  std::printf("rate at step 4 %.6g, at step 5 after moving the end from 6 to 20: %.6g (a fresh 20-step run: %.6g)\n",
              rate_at_4, rate_at_5, train::LearningRateSchedule(longer.optimizer, 20).at(5));
  EXPECT_LT(rate_at_5, rate_at_4);
  EXPECT_GT(rate_at_5, 0.95 * rate_at_4);  // a 16-step cosine from the rate at step 4 moves little in one step
  EXPECT_NEAR(resumed.schedule().at(20), config.optimizer.learning_rate * config.optimizer.final_lr_fraction, 1e-12);

  tat::TatTrainConfig changed = config;
  changed.optimizer.weight_decay = 0.5;
  tat::TatTrainer other(changed, cache, "walks", testing::tiny_frozen_owo(), nullptr, torch::kCPU);
  try {
    other.resume(checkpoint);
    FAIL() << "resumed with another weight decay";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'optimizer.weight_decay' (checkpoint 0.0, now 0.5)"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(tat::TatTrainer(config, cache, "walks", testing::tiny_frozen_owo(), nullptr, torch::kCPU).resume(dir / "none"),
               InputError);
}

// What the trainers embed each step: the corpus's rigs, kept before the first
// step, come back as embedding the batch afresh gives them; augmented rigs and
// rigs of test clips are embedded as they come.
TEST(RememberedSkeletonEmbeddings, ReadLikeFreshOnesAndKeepOnlyTheCorpusRigs) {
  torch::set_num_threads(1);
  DatasetCache cache = walk_cache();
  ASSERT_EQ(cache.skeletons.size(), 8u);
  for (CacheClip& clip : cache.clips) {
    if (clip.skeleton >= 6) clip.split = Split::Test;
  }
  owo::OwoPretrainer owo = testing::tiny_frozen_owo();
  tat::RememberedSkeletonEmbeddings remembered(owo->encoder, nullptr, cache, size_t{1} << 20);
  EXPECT_EQ(remembered.kept_rigs(), 6u);
  const auto batch_of = [&](const std::vector<int>& skeletons, const std::vector<uint8_t>& augmented) {
    Batch batch;
    for (const int s : skeletons) {
      Skeleton skeleton = cache.skeletons[static_cast<size_t>(s)].skeleton;
      if (augmented[batch.skeletons.size()]) skeleton.offsets[1] *= 1.5;  // as a length augmentation would
      batch.skeletons.push_back(skeleton);
      batch.canonical_names.push_back(cache.skeletons[static_cast<size_t>(s)].canonical_names);
    }
    batch.augmented = augmented;
    return batch;
  };
  const std::vector<std::pair<std::vector<int>, std::vector<uint8_t>>> batches = {
      {{0, 1, 1}, {0, 0, 1}}, {{1, 7, 2, 0}, {1, 0, 0, 0}}, {{2, 0, 5}, {0, 0, 0}}, {{2, 6}, {1, 0}}};
  for (const auto& [rigs, augmented] : batches) {
    const Batch batch = batch_of(rigs, augmented);
    const at::Tensor read = remembered.embed(batch);
    const at::Tensor fresh = tat::embed_skeletons(*owo->encoder, batch.skeletons, batch.canonical_names, nullptr);
    ASSERT_EQ(read.sizes(), fresh.sizes());
    EXPECT_FALSE(read.is_inference());
    EXPECT_LT((read - fresh).abs().max().item<double>(), 1e-5 * fresh.abs().max().item<double>());
    // An augmented rig is read as itself, not as the kept rig it came from.
    for (size_t i = 0; i < rigs.size(); ++i) {
      if (!augmented[i]) continue;
      const CachedSkeleton& rig = cache.skeletons[static_cast<size_t>(rigs[i])];
      const at::Tensor unaugmented = tat::embed_skeletons(*owo->encoder, {rig.skeleton}, {rig.canonical_names}, nullptr)[0];
      EXPECT_GT((read[static_cast<int64_t>(i)].narrow(0, 0, rig.skeleton.joint_count()) - unaugmented).abs().max().item<double>(),
                1e-4);
    }
  }
  EXPECT_EQ(tat::RememberedSkeletonEmbeddings(owo->encoder, nullptr, cache, 64).kept_rigs(), 0u);
}

TEST(TatTrainConfig, NotesAreAllowedEverywhereAndUnknownFieldsAreNamed) {
  const nlohmann::json noted = {{"comment", "laptop"},
                                {"model", {{"comment", "small"}, {"quantizer", {{"comment", "4 x 256"}}}}},
                                {"optimizer", {{"comment", "as OwO"}, {"learning_rate", 1e-3}}}};
  EXPECT_EQ(tat::tat_train_config_from_json(noted, "t.json").optimizer.learning_rate, 1e-3);
  try {
    tat::tat_train_config_from_json({{"optimizer", {{"lr", 1e-3}}}}, "t.json");
    FAIL() << "accepted optimizer.lr";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.json: field 'optimizer.lr' is not a known field (known here: "),
              std::string::npos)
        << e.what();
  }
}

TEST(TatTrainConfig, OnlyTheCadenceMayChangeOnResume) {
  EXPECT_EQ(train::fields_that_may_change<tat::TatTrainConfig>(),
            (std::set<std::string>{"steps", "log_every", "validate_every", "checkpoint_every"}));
}

TEST(TatTrainConfig, TheShippedConfigsReadAndWriteBackTheirOwnValues) {
  for (const char* name : {"tat_cpu.json", "tat_gpu.json"}) {
    const std::string path = (std::filesystem::path(__FILE__).parent_path().parent_path() / "configs" / name).string();
    const nlohmann::json file = nlohmann::json::parse(read_file(path));
    const tat::TatTrainConfig config = tat::read_tat_train_config(path);
    const nlohmann::json written = train::write_config(config);
    // Every value the file gives comes back unchanged (comments aside).
    const nlohmann::json given = file.flatten();
    for (auto it = given.begin(); it != given.end(); ++it) {
      if (it.key().find("comment") != std::string::npos) continue;
      EXPECT_EQ(written.at(nlohmann::json::json_pointer(it.key())), it.value()) << name << " " << it.key();
    }
    EXPECT_EQ(train::write_config(tat::tat_train_config_from_json(written, path)), written) << name;
  }
}

}  // namespace
}  // namespace nec

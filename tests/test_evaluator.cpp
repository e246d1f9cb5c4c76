// evaluator/: the contrastive loss on known inputs, the motion encoder's
// independence from padding, training that learns to match captions, a
// resumed run that takes the steps of one that never stopped, the best
// checkpoint kept, and checkpoints that load back or fail with a hint.
#include "nec/evaluator/evaluator.h"
#include "nec/evaluator/retrieval_index.h"
#include "nec/evaluator/t2m.h"
#include "nec/evaluator/training.h"

#include "nec/motion/bvh.h"
#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/corpus/preprocess.h"
#include "nec/train/config_fields.h"
#include "nec/train/loop.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "test_support.h"
#include "tat_support.h"
#include "text_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace nec {
namespace {

namespace fs = std::filesystem;
using evaluator::EvaluatorTrainConfig;
using evaluator::EvaluatorTrainer;

// Dogs and people that walk, turn or run (trot), three of each, 2 s; `val`
// clips of them (the last seeds) go to the val split.
DatasetCache action_cache(bool with_validation) {
  struct Kind {
    zoo::BodyPlan plan;
    zoo::Action action;
    double turn_rate;
    const char* caption;
  };
  const std::vector<Kind> kinds{{zoo::BodyPlan::Quadruped, zoo::Action::Walk, 0, "a dog walks forward"},
                                {zoo::BodyPlan::Quadruped, zoo::Action::Turn, 90, "a dog turns to the left"},
                                {zoo::BodyPlan::Quadruped, zoo::Action::Trot, 0, "a dog trots forward"},
                                {zoo::BodyPlan::Biped, zoo::Action::Walk, 0, "a person walks forward"},
                                {zoo::BodyPlan::Biped, zoo::Action::Turn, 90, "a person turns to the left"},
                                {zoo::BodyPlan::Biped, zoo::Action::Run, 0, "a person runs forward"}};
  std::vector<CacheEntry> entries;
  for (size_t k = 0; k < kinds.size(); ++k) {
    for (int seed = 0; seed < 4; ++seed) {
      const zoo::Creature creature = zoo::make_creature(kinds[k].plan, 10 + static_cast<uint64_t>(seed));
      zoo::MotionSpec spec;
      spec.action = kinds[k].action;
      spec.turn_rate = kinds[k].turn_rate;
      spec.speed = kinds[k].action == zoo::Action::Turn ? 0.0 : 0.8;
      spec.seconds = 2.0;
      spec.seed = static_cast<uint64_t>(seed);
      const std::string source = "zoo/k" + std::to_string(k) + "_s" + std::to_string(seed) + ".bvh";
      CacheEntry entry;
      entry.prepared = preprocess(Clip{creature.skeleton, zoo::synthesize_motion(creature, spec).motion, {}}, source);
      entry.source = source;
      entry.dataset = "zoo";
      entry.captions = {kinds[k].caption};
      entries.push_back(std::move(entry));
    }
  }
  CacheOptions options;
  options.split.val_fraction = 0.0;
  options.split.test_fraction = 0.0;
  DatasetCache cache = build_cache(entries, options);
  if (with_validation) {
    for (CacheClip& clip : cache.clips) {
      if (clip.source.find("_s3") != std::string::npos) clip.split = Split::Val;
    }
  }
  return cache;
}


class EvaluatorTest : public testing::CorpusTextTest {
 protected:
  EvaluatorTest() : vectors_(text::WordVectors::load(vectors_path())) {}

  text::CaptionReader reader_for(EvaluatorTrainConfig config) const {
    return text::CaptionReader::for_training(config.model.text, pieces_path());
  }

  EvaluatorTrainConfig small_config() const {
    EvaluatorTrainConfig config;
    const text::PieceModel pieces = text::PieceModel::load(pieces_path());
    config.model.motion.joint_embedding_dim = 16;
    config.model.motion.dim = 32;
    config.model.motion.heads = 2;
    config.model.motion.feedforward = 64;
    config.model.motion.temporal_layers = 1;
    config.model.motion.max_steps = 16;
    config.model.motion.output_dim = 32;
    config.model.text.vocab_size = pieces.vocab_size();
    config.model.text.word_dim = 16;
    config.model.text.dim = 32;
    config.model.text.heads = 2;
    config.model.text.feedforward = 64;
    config.model.text.layers = 1;
    config.model.text.max_pieces = 16;
    config.model.text.output_dim = 32;
    config.optimizer.learning_rate = 3e-3;
    config.optimizer.warmup_steps = 5;
    config.data.window_frames = 32;
    config.data.augment.probability = 0.3;
    config.data.joint_buckets = 0;
    config.batch_size = 12;
    config.steps = 150;
    config.seed = 5;
    return config;
  }
  text::WordVectors vectors_;
};

TEST(ContrastiveLoss, MatchesItsClosedForm) {
  // Two orthogonal pairs: logits s on the diagonal, 0 off it; each row's loss is log(1 + e^-s).
  const at::Tensor e = torch::eye(2);
  const at::Tensor diagonal = torch::eye(2).to(torch::kBool);
  for (const double s : {1.0, 5.0}) {
    const double expected = std::log(1.0 + std::exp(-s));
    const double got = evaluator::contrastive_loss(e, e, torch::tensor(s), diagonal).item<double>();
    EXPECT_NEAR(got, expected, 1e-6) << "scale " << s << ": difference " << got - expected;
  }
  // Equal captions are both targets: half the mass on each; with identical
  // embeddings the loss is then log 2 whatever the scale, its minimum.
  const at::Tensor same = torch::ones({2, 2}, torch::kBool);
  const at::Tensor one = torch::tensor({{1.0f, 0.0f}, {1.0f, 0.0f}});
  const double got = evaluator::contrastive_loss(one, one, torch::tensor(10.0), same).item<double>();
  EXPECT_NEAR(got, std::log(2.0), 1e-6);
  // Swapping the texts of two distinct pairs raises the loss.
  const at::Tensor swapped = torch::tensor({{0.0f, 1.0f}, {1.0f, 0.0f}});
  EXPECT_GT(evaluator::contrastive_loss(e, swapped, torch::tensor(5.0), diagonal).item<double>(), 4.0);
}

TEST(CaptionTeacherLoss, IsZeroWhereTheHeadKeepsTheTeachersSimilaritiesAndMatchesItsClosedForm) {
  const double temperature = 0.5, r = 1.0 / std::sqrt(2.0);
  const auto loss = [&](const at::Tensor& text, const at::Tensor& teacher) {
    return evaluator::caption_teacher_loss(text, teacher, temperature).item<double>();
  };
  const at::Tensor teacher = torch::tensor({{1.0, 0.0}, {0.0, 1.0}, {r, r}}, torch::kDouble);
  EXPECT_NEAR(loss(teacher, teacher), 0.0, 1e-9);
  // The head may be any rotation of the teacher, in another width: only the similarities count.
  const at::Tensor turn = torch::tensor({{0.6, 0.8, 0.0}, {-0.8, 0.6, 0.0}}, torch::kDouble);
  EXPECT_NEAR(loss(teacher.matmul(turn), teacher), 0.0, 1e-9);
  // A head that says the three captions are one: each row's head distribution is even over the other two.
  // The teacher's rows 0 and 1 put softmax(0, r / T) on their others, row 2 even: KL = sum p log(2 p).
  const at::Tensor one = torch::full({3, 2}, r, torch::kDouble);
  const double high = 1.0 / (1.0 + std::exp(-r / temperature)), low = 1.0 - high;
  const double row = high * std::log(2.0 * high) + low * std::log(2.0 * low);
  EXPECT_NEAR(loss(one, teacher), 2.0 * row / 3.0, 1e-9);
  EXPECT_GT(row, 0.01);
  // Gradient steps on a free head bring it to the teacher's similarities.
  at::Tensor free = torch::randn({3, 4}, torch::kDouble).requires_grad_(true);
  torch::optim::Adam adam({free}, torch::optim::AdamOptions(0.05));
  const double first = loss(torch::nn::functional::normalize(free, torch::nn::functional::NormalizeFuncOptions().dim(1)), teacher);
  for (int step = 0; step < 300; ++step) {
    adam.zero_grad();
    const at::Tensor unit = torch::nn::functional::normalize(free, torch::nn::functional::NormalizeFuncOptions().dim(1));
    evaluator::caption_teacher_loss(unit, teacher, temperature).backward();
    adam.step();
  }
  const double last = loss(torch::nn::functional::normalize(free, torch::nn::functional::NormalizeFuncOptions().dim(1)), teacher);
  EXPECT_LT(last, 1e-3) << "from " << first;
}

TEST(MotionEncoder, AClipsEmbeddingDoesNotDependOnWhatItIsBatchedWith) {
  torch::manual_seed(2);
  evaluator::MotionEncoderConfig config;
  config.joint_embedding_dim = 8;
  config.dim = 16;
  config.heads = 2;
  config.feedforward = 32;
  config.max_steps = 8;
  evaluator::MotionEncoder encoder(config);
  encoder->eval();
  torch::NoGradGuard no_grad;
  // Item 0: 3 joints, 10 frames; item 1: 5 joints, 24 frames.
  at::Tensor features = torch::randn({2, 24, 5, 9});
  at::Tensor joint_mask = torch::ones({2, 5}, torch::kBool);
  joint_mask[0].narrow(0, 3, 2).fill_(false);
  at::Tensor frame_mask = torch::ones({2, 24}, torch::kBool);
  frame_mask[0].narrow(0, 10, 14).fill_(false);
  const at::Tensor joints = torch::randn({2, 5, 8});
  const at::Tensor both = encoder->forward(features, joint_mask, frame_mask, joints);
  const at::Tensor alone = encoder->forward(features[0].narrow(0, 0, 10).narrow(1, 0, 3).unsqueeze(0),
                                            joint_mask[0].narrow(0, 0, 3).unsqueeze(0),
                                            frame_mask[0].narrow(0, 0, 10).unsqueeze(0),
                                            joints[0].narrow(0, 0, 3).unsqueeze(0));
  const double difference = (both[0] - alone[0]).abs().max().item<double>();
  EXPECT_LT(difference, 1e-5) << "padding changed the embedding by " << difference;
  // What sits in the padding does not matter either.
  at::Tensor noisy = features.clone();
  noisy[0].narrow(0, 10, 14).normal_();
  noisy[0].narrow(1, 3, 2).normal_();
  const double noise = (encoder->forward(noisy, joint_mask, frame_mask, joints)[0] - both[0]).abs().max().item<double>();
  EXPECT_LT(noise, 1e-5) << noise;
  EXPECT_THROW(encoder->forward(torch::zeros({1, 40, 3, 9}), torch::ones({1, 3}, torch::kBool),
                                torch::ones({1, 40}, torch::kBool), torch::zeros({1, 3, 8})),
               std::invalid_argument);
}

TEST_F(EvaluatorTest, TrainingLearnsToFindTheCaptionOfEachMotion) {
  const DatasetCache cache = action_cache(false);
  const EvaluatorTrainConfig config = small_config();
  EvaluatorTrainer trainer(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
  const auto retrieval = [&] {
    trainer.model()->eval();
    const std::vector<int> clips = cache.clips_in(Split::Train);
    std::vector<std::string> captions;
    for (const int clip : clips) captions.push_back(cache.clips[static_cast<size_t>(clip)].captions[0]);
    const at::Tensor text =
        evaluator::embed_captions(*trainer.model(), reader_for(config), &vectors_, captions, "t", torch::kCPU);
    const at::Tensor motion = evaluator::embed_clips(*trainer.model(), *testing::tiny_frozen_owo()->encoder, nullptr, cache, clips, torch::kCPU);
    trainer.model()->train();
    // Each motion's best caption is its own kind's (6 kinds, 4 clips each).
    const at::Tensor best = motion.matmul(text.t()).argmax(1);
    int correct = 0;
    for (int64_t i = 0; i < best.size(0); ++i) correct += captions[static_cast<size_t>(best[i].item<int64_t>())] == captions[static_cast<size_t>(i)];
    return static_cast<double>(correct) / static_cast<double>(best.size(0));
  };
  const double before = retrieval();
  double first = 0, last = 0;
  for (int64_t step = 1; step <= config.steps; ++step) {
    const train::LossTerms terms = trainer.step(step);
    if (step == 1) first = terms[0].second;
    last = terms[0].second;
  }
  const double after = retrieval();
  // Each batch holds about 2 clips of a kind: the loss cannot go below log 2 = 0.69.
  EXPECT_LT(last, 0.6 * first) << "loss " << first << " -> " << last;
  EXPECT_GE(after, 0.75) << "top-1 caption accuracy " << before << " -> " << after << " (chance 1/6)";
}

TEST_F(EvaluatorTest, AResumedRunTakesTheStepsOfOneThatNeverStoppedAndKeepsTheBest) {
  const DatasetCache cache = action_cache(true);
  EvaluatorTrainConfig config = small_config();
  config.steps = 6;
  config.validate_every = 2;
  config.checkpoint_every = 3;
  config.log_every = 0;
  const testing::TempDir dir;
  EvaluatorTrainer straight(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
  ASSERT_TRUE(straight.has_validation());
  std::vector<double> straight_losses;
  for (int64_t step = 1; step <= 6; ++step) straight_losses.push_back(straight.step(step)[0].second);

  EvaluatorTrainer first(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
  train::TrainingHooks hooks = first.hooks(dir / "run");
  for (int64_t step = 1; step <= 3; ++step) {
    hooks.step(step);
    if (step == 2) hooks.validate(step);
  }
  hooks.checkpoint(3);
  ASSERT_TRUE(fs::exists(fs::path(dir / "run") / "best" / "config.json"));
  EXPECT_EQ(first.best_step(), 2);
  {  // The same model validated again ties: the later step is the best (it has trained at least as long).
    EvaluatorTrainer tied(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
    train::TrainingHooks tied_hooks = tied.hooks(dir / "tied");
    tied_hooks.validate(2);
    tied_hooks.validate(4);
    EXPECT_EQ(tied.best_step(), 4);
  }

  EvaluatorTrainer resumed(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
  EXPECT_EQ(resumed.resume(dir / "run"), 3);
  EXPECT_EQ(resumed.best_step(), 2);
  for (int64_t step = 4; step <= 6; ++step) {
    const double loss = resumed.step(step)[0].second;
    EXPECT_NEAR(loss, straight_losses[static_cast<size_t>(step - 1)], 1e-5) << "step " << step;
  }
  // A later checkpoint without a better validation keeps the best it had.
  resumed.save(dir / "run", 6);
  const evaluator::LoadedEvaluator best = evaluator::load_evaluator_checkpoint(fs::path(dir / "run") / "best");
  EXPECT_EQ(best.info.training_step, 2);
  EXPECT_EQ(best.info.best_step, 2);
}

TEST_F(EvaluatorTest, ACheckpointLoadsBackToTheSameEmbeddingsOrFailsWithAHint) {
  const DatasetCache cache = action_cache(false);
  EvaluatorTrainConfig config = small_config();
  EvaluatorTrainer trainer(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
  trainer.step(1);
  const testing::TempDir dir;
  trainer.save(dir / "eval", 1);
  trainer.model()->eval();
  const at::Tensor expected = evaluator::embed_clips(*trainer.model(), *testing::tiny_frozen_owo()->encoder, nullptr, cache, {0, 5}, torch::kCPU);
  evaluator::EvaluatorSession session(evaluator::load_evaluator_checkpoint(dir / "eval"),
                                      text::WordVectors::load(vectors_path()), torch::kCPU);
  const double difference = (session.embed_clips(cache, {0, 5}) - expected).abs().max().item<double>();
  EXPECT_LT(difference, 1e-6) << difference;
  const at::Tensor texts = session.embed_captions({"a dog walks forward"}, "query");
  EXPECT_NEAR(texts.norm().item<double>(), 1.0, 1e-5);
  EXPECT_THROW(session.embed_captions({"   "}, "query"), InputError);

  try {
    evaluator::load_evaluator_checkpoint(dir / "missing");
    FAIL() << "loaded a missing checkpoint";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nec train evaluator"), std::string::npos) << e.what();
  }
  // A checkpoint of another kind names what it is.
  write_file_atomic(fs::path(dir / "eval") / "config.json", R"({"format": "nec-tat", "version": 9})");
  try {
    evaluator::load_evaluator_checkpoint(dir / "eval");
    FAIL() << "loaded a TAT config as an evaluator";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nec-tat"), std::string::npos) << e.what();
  }
}

TEST_F(EvaluatorTest, TheRetrievalIndexIsStoredOnceAndRebuiltForAnotherEvaluator) {
  const testing::TempDir dir;
  save_cache(action_cache(false), dir / "cache");
  const DatasetCache cache = read_cache(dir / "cache");
  EvaluatorTrainer trainer(small_config(), cache, "actions", testing::tiny_frozen_owo(), reader_for(small_config()), &vectors_,
                           torch::kCPU);
  trainer.step(1);
  trainer.save(dir / "eval", 1);
  const auto open = [&] {
    evaluator::EvaluatorSession session(evaluator::load_evaluator_checkpoint(dir / "eval"),
                                        text::WordVectors::load(vectors_path()), torch::kCPU);
    return evaluator::open_retrieval_index(session, cache, dir / "eval");
  };
  const evaluator::OpenedIndex first = open();
  EXPECT_TRUE(first.built && first.stored) << first.note;
  EXPECT_EQ(first.index.clips.size(), cache.clips.size());
  EXPECT_EQ(first.index.captions.size(), 6u);  // six distinct captions
  // Each clip's captions, and their sentence-encoder vectors.
  ASSERT_EQ(first.index.clip_captions.size(), cache.clips.size());
  for (size_t clip = 0; clip < cache.clips.size(); ++clip) {
    ASSERT_EQ(first.index.clip_captions[clip].size(), cache.clips[clip].captions.size());
    for (size_t c = 0; c < cache.clips[clip].captions.size(); ++c) {
      EXPECT_EQ(first.index.captions[static_cast<size_t>(first.index.clip_captions[clip][c])], cache.clips[clip].captions[c]);
    }
  }
  EXPECT_EQ(first.index.text_dim, 512);
  EXPECT_EQ(first.index.caption_texts.size(), 6u * 512);
  const evaluator::OpenedIndex second = open();
  EXPECT_FALSE(second.built);
  EXPECT_EQ(second.index.clip_embeddings, first.index.clip_embeddings);
  // The caption "a dog trots forward" finds the dog trots first.
  evaluator::EvaluatorSession session(evaluator::load_evaluator_checkpoint(dir / "eval"),
                                      text::WordVectors::load(vectors_path()), torch::kCPU);
  const at::Tensor query = session.embed_captions({"a dog trots forward"}, "query");
  const std::vector<evaluator::Match> top = second.index.nearest_clips(query, 1, {});
  ASSERT_EQ(top.size(), 1u);
  EXPECT_NEAR(top[0].score, query.matmul(session.embed_clips(cache, {second.index.clips[top[0].row]}).t()).item<float>(), 1e-5);
  // By the caption texts alone, each distinct caption finds a clip that has it.
  for (const std::string& caption : second.index.captions) {
    const evaluator::CaptionBlend blend{evaluator::caption_text_vectors({caption}, "query"), 1.f};
    const std::vector<evaluator::Match> by_text = second.index.nearest_clips(session.embed_captions({caption}, "query"), 1, {}, blend);
    ASSERT_EQ(by_text.size(), 1u);
    const std::vector<std::string>& has = cache.clips[static_cast<size_t>(second.index.clips[by_text[0].row])].captions;
    EXPECT_NE(std::find(has.begin(), has.end(), caption), has.end()) << caption;
  }
  // Another evaluator: another key, a new index.
  trainer.step(2);
  trainer.save(dir / "eval", 2);
  const evaluator::OpenedIndex third = open();
  EXPECT_TRUE(third.built);
  EXPECT_NE(third.path, first.path);
  // A damaged file is rebuilt, with the reason.
  write_file_atomic(third.path, "garbage");
  const evaluator::OpenedIndex fourth = open();
  EXPECT_TRUE(fourth.built && fourth.stored);
  EXPECT_NE(fourth.note.find("bad magic"), std::string::npos) << fourth.note;
}

TEST_F(EvaluatorTest, RealClipsWrittenAsGeneratedOnesScoreLikeTheRealOnes) {
  // The reference clips themselves, written as BVH with their captions, twice
  // each: the same distribution (FID ~ 0), every window covered, nothing novel,
  // the same jitter, and two identical samples per caption (Multimodality 0).
  const testing::TempDir dir;
  const DatasetCache cache = action_cache(false);
  EvaluatorTrainer trainer(small_config(), cache, "actions", testing::tiny_frozen_owo(), reader_for(small_config()), &vectors_,
                           torch::kCPU);
  trainer.save(dir / "eval", 0);
  evaluator::EvaluatorSession session(evaluator::load_evaluator_checkpoint(dir / "eval"),
                                      text::WordVectors::load(vectors_path()), torch::kCPU);
  // In zoo folders named after the body plan, as scripts/eval_generation.sh writes them.
  for (int clip = 0; clip < cache.clip_count(); ++clip) {
    const Clip real = cache.clip(clip);
    const bool dog = cache.clips[static_cast<size_t>(clip)].captions[0].find("dog") != std::string::npos;
    const fs::path folder = fs::path(dir / "generated") / "zoo" / (dog ? "c000_quadruped" : "c001_biped");
    fs::create_directories(folder);
    for (const char* sample : {"a", "b"}) {
      const fs::path file = folder / ("clip" + std::to_string(clip) + sample + ".bvh");
      write_bvh(file.string(), real.skeleton, real.motion);
      write_file_atomic(fs::path(file).replace_extension(".txt").string(), cache.clips[static_cast<size_t>(clip)].captions[0] + "\n");
    }
  }
  const std::vector<evaluator::GeneratedClip> generated = evaluator::read_generated(dir / "generated", cache.fps, UpAxis::Auto);
  ASSERT_EQ(generated.size(), 2 * cache.clips.size());
  EXPECT_EQ(generated[0].group, "zoo");
  EXPECT_EQ(generated[0].plan, "quadruped");
  EXPECT_EQ(generated.back().plan, "biped");
  evaluator::T2mOptions options;
  options.window_stride = 10;
  const evaluator::T2mReport report = evaluator::evaluate_t2m(session, generated, cache, Split::Train, options);
  ASSERT_EQ(report.rows.size(), 2u);  // zoo, all
  const evaluator::T2mRow& zoo = report.rows[0];
  EXPECT_EQ(zoo.name, "zoo");
  EXPECT_EQ(zoo.generated, 48);
  EXPECT_EQ(zoo.reference, 24);
  EXPECT_TRUE(zoo.has_precision);
  EXPECT_EQ(zoo.batch_size, 32);
  EXPECT_FALSE(zoo.has_within_plan) << "each plan has 24 generated clips, under a batch of 32";
  EXPECT_LT(zoo.fid, 1e-3) << "FID of the real clips against themselves";
  EXPECT_NEAR(zoo.diversity, zoo.reference_diversity, 0.25 * zoo.reference_diversity);
  EXPECT_EQ(zoo.multimodality_captions, 6);
  EXPECT_LT(zoo.multimodality, zoo.reference_diversity) << "identical samples of a caption, only other clips of its kind differ";
  EXPECT_EQ(zoo.coverage_pairs, 48 * 4);  // each generated clip against the 4 real clips of its caption
  EXPECT_GT(zoo.coverage_auc, 0.5);
  EXPECT_LT(zoo.novelty_auc, 0.5);
  EXPECT_NEAR(zoo.jitter, zoo.reference_jitter, 0.02 * zoo.reference_jitter)
      << zoo.jitter << " against " << zoo.reference_jitter;
  EXPECT_GT(zoo.reference_turning, 5.0) << "the zoo's clips turn their joints";
  EXPECT_NEAR(zoo.turning, zoo.reference_turning, 0.02 * zoo.reference_turning)
      << zoo.turning << " against " << zoo.reference_turning;
  const std::string table = evaluator::to_markdown(report);
  EXPECT_NE(table.find("| zoo | 48 / 24 |"), std::string::npos) << table;

  // Batches of 16: one batch within each plan per repeat. Across creatures, a
  // clip is compared with the walks (turns) of dogs and people alike: 8 real
  // clips for walk and turn captions, 4 for trot and run; 8 generated clips of
  // each of the 6 captions: 8 * (8 + 8 + 4 + 8 + 8 + 4) pairs.
  options.batch_size = 16;
  options.coverage_across_creatures = true;
  const evaluator::T2mRow across = evaluator::evaluate_t2m(session, generated, cache, Split::Train, options).rows[0];
  ASSERT_TRUE(across.has_within_plan);
  EXPECT_EQ(across.within_plan.batches_per_repeat, 2);
  EXPECT_TRUE(across.within_plan.skipped_groups.empty());
  EXPECT_EQ(across.coverage_pairs, 320);
  EXPECT_GT(across.coverage_auc, 0.0);

  // The same clips held in their first frame: a statue turns nothing, against the same real turning.
  {
    const std::vector<evaluator::GeneratedClip> moving = evaluator::read_generated(dir / "generated", cache.fps, UpAxis::Auto);
    for (const evaluator::GeneratedClip& clip : moving) {
      Motion still = clip.prepared.clip.motion;
      for (int t = 1; t < still.frame_count; ++t) {
        for (int j = 0; j < still.joint_count; ++j) {
          still.rotation(t, j) = still.rotation(0, j);
          still.translation(t, j) = still.translation(0, j);
        }
      }
      write_bvh(clip.path, clip.prepared.clip.skeleton, still);
    }
    const evaluator::T2mRow statue =
        evaluator::evaluate_t2m(session, evaluator::read_generated(dir / "generated", cache.fps, UpAxis::Auto), cache,
                                Split::Train, options).rows[0];
    EXPECT_LT(statue.turning, 0.01 * zoo.reference_turning);
    EXPECT_DOUBLE_EQ(statue.reference_turning, zoo.reference_turning);
  }

  // A generated file without its caption is refused by name.
  fs::remove(fs::path(generated[0].path).replace_extension(".txt"));
  try {
    evaluator::read_generated(dir / "generated", cache.fps, UpAxis::Auto);
    FAIL() << "read a generated clip without a caption";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fs::path(generated[0].path).filename().string() + ": has no caption"),
              std::string::npos) << e.what();
  }
}

TEST_F(EvaluatorTest, ACaptionLongerThanTheTextEncoderTakesIsRefusedBeforeTraining) {
  const DatasetCache cache = action_cache(false);
  EvaluatorTrainConfig config = small_config();
  config.model.text.max_pieces = 4;
  try {
    EvaluatorTrainer(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
    FAIL() << "accepted captions longer than the encoder takes";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("more than model.text.max_pieces = 4 (raise it in the config)"), std::string::npos)
        << e.what();
  }
}

TEST_F(EvaluatorTest, CaptionSynonymsComeFromTheTrainCaptionsWordsAndTrainingRunsOnThem) {
  const DatasetCache cache = action_cache(false);
  EvaluatorTrainConfig config = small_config();
  config.captions.synonym_probability = 1.0;
  EvaluatorTrainer trainer(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), &vectors_, torch::kCPU);
  // The corpus vectors put "hound" next to "dog" and "sprints" next to "runs"; their other words lie at
  // random angles, of which at most one passes min_cosine 0.6 here (a seeded draw).
  EXPECT_EQ(trainer.synonyms().synonyms_of("dog"), (std::vector<std::string>{"hound"}));
  EXPECT_EQ(trainer.synonyms().synonyms_of("runs"), (std::vector<std::string>{"sprints"}));
  EXPECT_EQ(trainer.synonyms().synonym_count(), trainer.synonyms().word_count());
  EXPECT_LE(trainer.synonyms().word_count(), 3u);
  for (int64_t step = 1; step <= 3; ++step) EXPECT_TRUE(std::isfinite(trainer.step(step)[0].second));

  config.captions.synonym_probability = 0.5;
  EXPECT_THROW(EvaluatorTrainer(config, cache, "actions", testing::tiny_frozen_owo(), reader_for(config), nullptr, torch::kCPU),
               std::invalid_argument);
  config.captions.synonym_probability = 1.5;
  try {
    config.validate();
    FAIL() << "accepted a synonym probability of 1.5";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("captions.synonym_probability"), std::string::npos) << e.what();
  }
}

TEST(EvaluatorTrainConfig, UnknownFieldsAreNamedAndOnlyTheCadenceMayChangeOnResume) {
  const testing::TempDir dir;
  write_file_atomic(dir / "c.json", R"({"comment": "ok", "model": {"motion": {"dimm": 3}}})");
  try {
    evaluator::read_evaluator_train_config(dir / "c.json");
    FAIL() << "read an unknown field";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("model.motion.dimm"), std::string::npos) << e.what();
  }
  const std::set<std::string> may_change = train::fields_that_may_change<EvaluatorTrainConfig>();
  EXPECT_EQ(may_change, (std::set<std::string>{"steps", "log_every", "validate_every", "checkpoint_every"}));
}

TEST(EvaluatorTrainConfig, TheCaptionTeacherNeedsTheSentenceEncoder) {
  EvaluatorTrainConfig config = evaluator::read_evaluator_train_config(
      (fs::path(__FILE__).parent_path().parent_path() / "configs" / "evaluator_cpu.json").string());
  ASSERT_EQ(config.model.text.backbone, text::kUseLiteBackbone);
  config.captions.teacher_weight = 0.5;
  EXPECT_NO_THROW(config.validate());
  config.model.text.backbone = text::kPiecesBackbone;
  config.model.text.word_dim = 100;
  config.model.text.layers = 1;
  try {
    config.validate();
    FAIL() << "a teacher for the pieces backbone";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("captions.teacher_weight"), std::string::npos) << e.what();
  }
  config.model.text.backbone = text::kUseLiteBackbone;
  config.model.text.word_dim = 0;
  config.model.text.layers = 0;
  config.captions.teacher_temperature = 0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
}

TEST(EvaluatorTrainConfig, TheShippedConfigReadsAndWritesBackItsOwnValues) {
  const std::string path = (fs::path(__FILE__).parent_path().parent_path() / "configs" / "evaluator_cpu.json").string();
  const nlohmann::json file = nlohmann::json::parse(read_file(path));
  const nlohmann::json written = train::write_config(evaluator::read_evaluator_train_config(path));
  const nlohmann::json given = file.flatten();
  for (auto it = given.begin(); it != given.end(); ++it) {
    if (it.key().find("comment") != std::string::npos) continue;
    EXPECT_EQ(written.at(nlohmann::json::json_pointer(it.key())), it.value()) << it.key();
  }
}

}  // namespace
}  // namespace nec

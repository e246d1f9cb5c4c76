// evaluator/retrieval*.h: body plans and masked creature words, the R-Precision
// table on constructed embeddings whose answers are known, and the retrieval
// index: nearest neighbours, a byte-exact round trip, damage refused, a stale
// index rebuilt.
#include "nec/evaluator/retrieval.h"
#include "nec/evaluator/retrieval_index.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/random.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <string>
#include <vector>

namespace nec {
namespace {

using evaluator::Embeddings;

CacheClip clip_at(const std::string& source, const std::string& dataset) {
  CacheClip clip;
  clip.source = source;
  clip.dataset = dataset;
  return clip;
}

TEST(Retrieval, BodyPlansComeFromTheZooFoldersElseTheDataset) {
  EXPECT_EQ(evaluator::body_plan_of(clip_at("zoo/seen/c033_fish/c033_fish_k00_attack.bvh", "zoo")), "fish");
  EXPECT_EQ(evaluator::body_plan_of(clip_at("zoo/held_out/c022_snake/a.bvh", "zoo_held_out")), "snake");
  EXPECT_EQ(evaluator::body_plan_of(clip_at("/data/bandai/set1/data/dataset-1_dash_proud_001.bvh", "bandai")), "bandai");
  EXPECT_EQ(evaluator::body_plan_of(clip_at("mann_dog/D1_001_KAN01_001.bvh", "dog")), "dog");
}

TEST(Retrieval, CreatureWordsAreMaskedWholeWordsOnly) {
  EXPECT_EQ(evaluator::mask_creature_words("a dog trots to the left"), "a creature trots to the left");
  EXPECT_EQ(evaluator::mask_creature_words("two spiders and a person"), "two creature and a creature");
  EXPECT_EQ(evaluator::mask_creature_words("someone bows politely"), "creature bows politely");
  // Not inside other words.
  EXPECT_EQ(evaluator::mask_creature_words("a dogged antelope walks"), "a dogged antelope walks");
}

// `n` clips in two datasets of two plans each; text and motion rows given by `make`.
struct Constructed {
  evaluator::RetrievalSet set;
  Embeddings text, motion;
};

Constructed constructed(int n, uint64_t seed, double noise) {
  Constructed c;
  SplitMix64 random(seed);
  c.motion = Embeddings(n, 8);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 8; ++d) c.motion(i, d) = random.uniform(-1, 1);
    c.set.clips.push_back(i);
    c.set.captions.push_back("caption " + std::to_string(i));
    c.set.datasets.push_back(i % 2 == 0 ? "zoo" : "dog");
    c.set.plans.push_back(i % 2 == 0 ? (i % 4 == 0 ? "spider" : "snake") : "dog");
  }
  c.text = c.motion;
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d < 8; ++d) c.text(i, d) += noise * random.uniform(-1, 1);
  }
  return c;
}

TEST(Retrieval, TheTableFindsExactMatchesAndItsFloorStaysAtChance) {
  const Constructed c = constructed(256, 4, 0.0);
  evaluator::RetrievalOptions options;
  const evaluator::RetrievalTable table = evaluator::retrieval_table(c.set, {c.text, c.text, c.motion}, options);
  ASSERT_EQ(table.rows.size(), 3u);  // dog, zoo, all
  EXPECT_EQ(table.rows[0].name, "dog");
  EXPECT_EQ(table.rows[2].name, "all");
  for (const evaluator::RetrievalRow& row : table.rows) {
    EXPECT_EQ(row.batch_size, 32);
    EXPECT_DOUBLE_EQ(row.mixed.top_k[0].mean, 1.0) << row.name;
    EXPECT_DOUBLE_EQ(row.masked.top_k[2].mean, 1.0) << row.name;
    ASSERT_TRUE(row.has_within_plan) << row.name;
    EXPECT_DOUBLE_EQ(row.within_plan.top_k[0].mean, 1.0) << row.name;
    // Shuffled captions: R@3 near 3/32 = 0.094.
    EXPECT_NEAR(row.floor.top_k[2].mean, 3.0 / 32, 0.05) << row.name << " floor " << row.floor.top_k[2].mean;
  }
  EXPECT_EQ(table.rows[2].clips, 256);
  EXPECT_NE(evaluator::to_markdown(table).find("| all | 256 | 32 | 1.000 / 1.000 / 1.000"), std::string::npos)
      << evaluator::to_markdown(table);
  EXPECT_EQ(evaluator::to_json(table)["rows"][2]["mixed"]["r_precision"][0]["mean"].get<double>(), 1.0);
}

TEST(Retrieval, SmallDatasetsUseTheirSizeAsTheBatchAndSayIt) {
  const Constructed c = constructed(20, 5, 0.0);
  const evaluator::RetrievalTable table = evaluator::retrieval_table(c.set, {c.text, c.text, c.motion}, {});
  ASSERT_EQ(table.rows.size(), 3u);
  EXPECT_EQ(table.rows[0].batch_size, 10);  // dog: 10 clips
  EXPECT_EQ(table.rows[2].batch_size, 20);
  // Plans of 5 clips cannot fill a batch of 10: no within-plan number for zoo.
  EXPECT_FALSE(table.rows[1].has_within_plan);
}

TEST(Retrieval, GivenCaptionsReplaceTheClipsOwnInListOrder) {
  const testing::TempDir dir;
  write_file_atomic(dir / "p.tsv", "# paraphrases\n\nb.bvh\tsomebody hurries onward\r\na.bvh\tbeast drifts aloft\n");
  const auto captions = evaluator::read_file_captions(dir / "p.tsv");
  ASSERT_EQ(captions.size(), 2u);
  EXPECT_EQ(captions[0], (std::pair<std::string, std::string>{"b.bvh", "somebody hurries onward"}));
  DatasetCache cache;
  cache.clips = {clip_at("zoo/c001_dragon/a.bvh", "zoo"), clip_at("bandai/b.bvh", "bandai"), clip_at("c.bvh", "dog")};
  evaluator::RetrievalSet set;
  set.clips = {0, 1, 2};
  set.captions = {"a dragon glides", "a person runs", "a dog sits"};
  set.datasets = {"zoo", "bandai", "dog"};
  set.plans = {"dragon", "bandai", "dog"};
  const evaluator::RetrievalSet given = evaluator::with_captions(set, cache, captions, "p.tsv");
  EXPECT_EQ(given.clips, (std::vector<int>{1, 0}));
  EXPECT_EQ(given.captions, (std::vector<std::string>{"somebody hurries onward", "beast drifts aloft"}));
  EXPECT_EQ(given.plans, (std::vector<std::string>{"bandai", "dragon"}));
  try {
    evaluator::with_captions(set, cache, {{"zzz.bvh", "x"}}, "p.tsv");
    FAIL() << "took a file that is not in the set";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'zzz.bvh' is not a captioned clip"), std::string::npos) << e.what();
  }
  write_file_atomic(dir / "bad.tsv", "a.bvh\tfine\nno tab here\n");
  try {
    evaluator::read_file_captions(dir / "bad.tsv");
    FAIL() << "read a line without a tab";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":2:"), std::string::npos) << e.what();
  }
  write_file_atomic(dir / "twice.tsv", "a.bvh\tone\na.bvh\ttwo\n");
  EXPECT_THROW(evaluator::read_file_captions(dir / "twice.tsv"), InputError);
}

// An index of n clips (embedding rows e_i) and m captions, by hand.
evaluator::RetrievalIndex hand_index() {
  evaluator::RetrievalIndex index;
  index.dim = 3;
  index.cache_key = 11;
  index.evaluator_key = 22;
  index.clips = {4, 7, 9};
  index.clip_embeddings = {1, 0, 0, 0, 1, 0, 0.6f, 0.8f, 0};
  index.captions = {"a dog walks", "a spider crawls"};
  index.caption_embeddings = {0, 0, 1, 1, 0, 0};
  index.text_dim = 2;
  index.caption_texts = {1, 0, 0, 1};
  index.clip_captions = {{0}, {1}, {}};  // clip 9 has no caption
  return index;
}

TEST(RetrievalIndex, NearestRowsComeBestFirstAndFiltersApply) {
  const evaluator::RetrievalIndex index = hand_index();
  const at::Tensor query = torch::tensor({{0.0f, 1.0f, 0.0f}});
  const std::vector<evaluator::Match> top = index.nearest_clips(query, 2, {});
  ASSERT_EQ(top.size(), 2u);
  EXPECT_EQ(top[0].row, 1);
  EXPECT_NEAR(top[0].score, 1.0f, 1e-6);
  EXPECT_EQ(top[1].row, 2);
  EXPECT_NEAR(top[1].score, 0.8f, 1e-6);
  const std::vector<evaluator::Match> kept = index.nearest_clips(query, 5, [](int clip) { return clip == 4; });
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].row, 0);
  const std::vector<evaluator::Match> captions = index.nearest_captions(torch::tensor({{1.0f, 0.0f, 0.0f}}), 1);
  ASSERT_EQ(captions.size(), 1u);
  EXPECT_EQ(index.captions[static_cast<size_t>(captions[0].row)], "a spider crawls");
  EXPECT_THROW(index.nearest_clips(torch::ones({1, 4}), 1, {}), std::invalid_argument);
}

TEST(RetrievalIndex, CaptionTextsReorderTheMotionsByTheirWeight) {
  const evaluator::RetrievalIndex index = hand_index();
  // Motions: clip 7 (row 1) 1.0, clip 9 (row 2) 0.8, clip 4 (row 0) 0. The query's text is the first caption's
  // ("a dog walks", clip 4's).
  const at::Tensor motion_query = torch::tensor({{0.0f, 1.0f, 0.0f}});
  evaluator::CaptionBlend blend{torch::tensor({{1.0f, 0.0f}}), 0.f};
  EXPECT_EQ(index.nearest_clips(motion_query, 1, {}, blend)[0].row, 1);  // weight 0: the motions alone
  // Standardized over the three clips, motion (0, 1, 0.8) -> (-1.39, 0.93, 0.46); the captions of the captioned
  // clips (1, 0) -> (1, -1); clip 9, without captions, takes its motion score for both parts.
  blend.weight = 1.f;
  std::vector<evaluator::Match> top = index.nearest_clips(motion_query, 3, {}, blend);
  ASSERT_EQ(top.size(), 3u);
  EXPECT_EQ(top[0].row, 0);
  EXPECT_NEAR(top[0].score, 1.f, 1e-5);
  EXPECT_EQ(top[1].row, 2);
  EXPECT_EQ(top[2].row, 1);
  // At equal weight: clip 4 0.5 (-1.39 + 1) = -0.19, clip 7 0.5 (0.93 - 1) = -0.04, clip 9 0.46.
  blend.weight = 0.5f;
  top = index.nearest_clips(motion_query, 3, {}, blend);
  ASSERT_EQ(top.size(), 3u);
  EXPECT_EQ(top[0].row, 2);
  EXPECT_NEAR(top[0].score, 0.2 / std::sqrt(0.56 / 3), 1e-5);
  EXPECT_EQ(top[1].row, 1);
  EXPECT_NEAR(top[1].score, 0.5 * (0.4 / std::sqrt(0.56 / 3) - 1), 1e-5);
  EXPECT_EQ(top[2].row, 0);
  blend.weight = 1.5f;
  EXPECT_THROW(index.nearest_clips(motion_query, 1, {}, blend), std::invalid_argument);
  blend.weight = 0.5f;
  blend.text = torch::ones({1, 3});
  EXPECT_THROW(index.nearest_clips(motion_query, 1, {}, blend), std::invalid_argument);
}

TEST(RetrievalIndex, BytesRoundTripAndDamageIsRefused) {
  const evaluator::RetrievalIndex index = hand_index();
  const std::string bytes = evaluator::serialize(index);
  const evaluator::RetrievalIndex back = evaluator::deserialize_retrieval_index(bytes, "x.index");
  EXPECT_EQ(back.clips, index.clips);
  EXPECT_EQ(back.clip_embeddings, index.clip_embeddings);
  EXPECT_EQ(back.captions, index.captions);
  EXPECT_EQ(back.caption_embeddings, index.caption_embeddings);
  EXPECT_EQ(back.text_dim, index.text_dim);
  EXPECT_EQ(back.caption_texts, index.caption_texts);
  EXPECT_EQ(back.clip_captions, index.clip_captions);
  EXPECT_EQ(back.cache_key, 11u);
  EXPECT_EQ(back.evaluator_key, 22u);
  EXPECT_EQ(evaluator::serialize(back), bytes);
  for (const size_t cut : {size_t{4}, size_t{40}, bytes.size() - 1}) {
    try {
      evaluator::deserialize_retrieval_index(bytes.substr(0, cut), "x.index");
      FAIL() << "read an index cut at " << cut;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("x.index"), std::string::npos) << e.what();
    }
  }
  std::string wrong = bytes;
  wrong[0] = 'X';
  EXPECT_THROW(evaluator::deserialize_retrieval_index(wrong, "x.index"), InputError);
  EXPECT_THROW(evaluator::deserialize_retrieval_index(bytes + "junk", "x.index"), InputError);
}

}  // namespace
}  // namespace nec

// gpt/: the text-to-token transformer. Generation with the KV cache gives the
// logits of the teacher-forced forward; nothing reads the future; a dropped
// caption is the unconditioned input; top-k / top-p and the draws on known
// numbers; sampling repeats by seed, row by row; and a tiny GPT learns which
// token sequence (and length) each caption means.
#include "nec/gpt/model.h"
#include "nec/gpt/sampling.h"
#include "nec/gpt/token_set.h"
#include "nec/gpt/training.h"
#include "nec/motion/error.h"

#include "text_encoder_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <vector>

namespace nec {
namespace {

using gpt::GptCondition;
using gpt::GptConfig;
using gpt::TokenGpt;

GptConfig tiny_config() {
  GptConfig c;
  c.codebook_layers = 3;
  c.codebook_size = 8;
  c.skeleton_dim = 4;
  c.dim = 32;
  c.layers = 2;
  c.heads = 2;
  c.feedforward = 64;
  c.max_steps = 12;
  c.dropout = 0.0;
  c.text.vocab_size = 20;
  c.text.word_dim = 0;
  c.text.dim = 16;
  c.text.layers = 1;
  c.text.heads = 2;
  c.text.feedforward = 32;
  c.text.max_pieces = 8;
  c.text.output_dim = 16;
  c.text.dropout = 0.0;
  c.text.piece_dropout = 0.0;
  return c;
}

using testing::piece_batch;

double max_difference(const at::Tensor& a, const at::Tensor& b) { return (a - b).abs().max().item<double>(); }

class GptTest : public ::testing::Test {
 protected:
  GptTest() {
    torch::manual_seed(3);
    model_ = TokenGpt(tiny_config());
    model_->eval();
    skeletons_ = torch::randn({2, gpt::skeleton_feature_width(4)});
    condition_ = model_->condition(piece_batch({{2, 3, 4}, {5, 6}}), skeletons_, {});
    codes_ = torch::randint(0, 8, {2, 6, 3}, torch::kInt64);
    targets_ = torch::cat({codes_, torch::randint(0, 8, {2, 1, 3}, torch::kInt64)}, 1);
  }
  TokenGpt model_{nullptr};
  at::Tensor skeletons_, codes_, targets_;
  GptCondition condition_;
};

TEST_F(GptTest, CachedStepsGiveTheLogitsOfTheWholeSequence) {
  torch::NoGradGuard no_grad;
  const gpt::GptLogits full = model_->forward(condition_, codes_, targets_);
  ASSERT_EQ(full.first.sizes(), (std::vector<int64_t>{2, 7, 9}));
  ASSERT_EQ(full.rest.sizes(), (std::vector<int64_t>{2, 7, 2, 8}));
  gpt::KvCache cache;
  at::Tensor h = model_->start(condition_, cache, {});
  double largest = 0;
  for (int64_t t = 0; t <= 6; ++t) {
    const at::Tensor step_targets = targets_.select(1, t);
    largest = std::max(largest, max_difference(model_->layer_logits(h, 0, step_targets.narrow(1, 0, 0)), full.first.select(1, t)));
    for (int64_t layer = 1; layer < 3; ++layer) {
      largest = std::max(largest, max_difference(model_->layer_logits(h, layer, step_targets.narrow(1, 0, layer)),
                                                 full.rest.select(1, t).select(1, layer - 1)));
    }
    if (t < 6) h = model_->advance(cache, codes_.select(1, t));
  }
  std::printf("largest difference, cached vs whole: %.3g\n", largest);
  EXPECT_LT(largest, 1e-4);

  // Starting from a context of 4 steps gives the output after them.
  gpt::KvCache from_context;
  const at::Tensor after_context = model_->start(condition_, from_context, codes_.narrow(1, 0, 4));
  const at::Tensor expected = full.first.select(1, 4);
  EXPECT_LT(max_difference(model_->layer_logits(after_context, 0, codes_.narrow(2, 0, 0).select(1, 0)), expected), 1e-4);
}

TEST_F(GptTest, NoOutputReadsALaterStep) {
  torch::NoGradGuard no_grad;
  at::Tensor changed = codes_.clone();
  changed.select(1, 4).fill_(7);
  changed.select(1, 5).fill_(6);
  const at::Tensor before = model_->forward(condition_, codes_, targets_).first;
  const at::Tensor after = model_->forward(condition_, changed, targets_).first;
  // Output t predicts step t from steps 0..t-1: outputs 0..4 do not read step 4.
  EXPECT_LT(max_difference(before.narrow(1, 0, 5), after.narrow(1, 0, 5)), 1e-6);
  EXPECT_GT(max_difference(before.select(1, 5), after.select(1, 5)), 1e-4);
}

TEST_F(GptTest, ADroppedCaptionIsTheUnconditionedInput) {
  torch::NoGradGuard no_grad;
  const at::Tensor drop = torch::ones({2}, torch::kBool);
  const GptCondition dropped_a = model_->condition(piece_batch({{2, 3, 4}, {5, 6}}), skeletons_, drop);
  const GptCondition dropped_b = model_->condition(piece_batch({{9, 9, 9, 9}, {11}}), skeletons_, drop);
  const GptCondition none = model_->unconditioned(skeletons_);
  const at::Tensor a = model_->forward(dropped_a, codes_, targets_).first;
  EXPECT_LT(max_difference(a, model_->forward(dropped_b, codes_, targets_).first), 1e-5);
  EXPECT_LT(max_difference(a, model_->forward(none, codes_, targets_).first), 1e-5);
  EXPECT_GT(max_difference(a, model_->forward(condition_, codes_, targets_).first), 1e-4);
}

TEST(GptSampling, TopKAndTopPKeepTheRightCodes) {
  gpt::SamplingOptions options;
  options.top_p = 1.0;
  options.top_k = 2;
  const at::Tensor p = gpt::sampling_probabilities(torch::tensor({{1.0f, 2.0f, 3.0f, 4.0f}}), options);
  const double e = std::exp(1.0);
  EXPECT_NEAR(p[0][0].item<double>(), 0.0, 1e-7);
  EXPECT_NEAR(p[0][1].item<double>(), 0.0, 1e-7);
  EXPECT_NEAR(p[0][3].item<double>(), e / (1 + e), 1e-6);

  options.top_k = 0;
  options.top_p = 0.7;
  const at::Tensor logits = torch::tensor({{0.15f, 0.5f, 0.05f, 0.3f}}).log();
  const at::Tensor q = gpt::sampling_probabilities(logits, options);
  EXPECT_NEAR(q[0][1].item<double>(), 0.625, 1e-6);
  EXPECT_NEAR(q[0][3].item<double>(), 0.375, 1e-6);
  EXPECT_NEAR(q[0][0].item<double>() + q[0][2].item<double>(), 0.0, 1e-7);
  options.top_p = 0.5;  // the most likely code alone holds 0.5
  EXPECT_NEAR(gpt::sampling_probabilities(logits, options)[0][1].item<double>(), 1.0, 1e-6);

  options.top_p = 1.0;
  options.temperature = 0.5;  // logits doubled
  const at::Tensor sharp = gpt::sampling_probabilities(torch::tensor({{0.0f, std::log(2.0f)}}), options);
  EXPECT_NEAR(sharp[0][1].item<double>(), 0.8, 1e-6);

  const at::Tensor probabilities = torch::tensor({{0.25, 0.25, 0.5}, {0.0, 1.0, 0.0}});
  EXPECT_EQ(gpt::draw_codes(probabilities, {0.1, 0.99}), (std::vector<int64_t>{0, 1}));
  EXPECT_EQ(gpt::draw_codes(probabilities, {0.3, 0.0}), (std::vector<int64_t>{1, 1}));
  EXPECT_EQ(gpt::draw_codes(probabilities, {0.9, 0.5}), (std::vector<int64_t>{2, 1}));
  options.temperature = 0;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

TEST_F(GptTest, SamplesRepeatBySeedRowByRow) {
  gpt::SamplingOptions options;
  options.seed = 11;
  options.guidance = 2.0;
  const GptCondition none = model_->unconditioned(skeletons_);
  gpt::SequenceLength length;
  length.steps = 20;  // longer than the window of 12: the sampler slides
  const std::vector<at::Tensor> both = gpt::sample_codes(*model_, condition_, &none, {}, length, options);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(both[0].sizes(), (std::vector<int64_t>{20, 3}));
  EXPECT_TRUE(both[0].ge(0).all().item<bool>() && both[0].lt(8).all().item<bool>());
  EXPECT_TRUE(torch::equal(both[0], gpt::sample_codes(*model_, condition_, &none, {}, length, options)[0]));
  // Row 1 alone, with seed + 1, draws what it drew in the batch.
  const at::Tensor row = torch::tensor({1}, torch::kInt64);
  gpt::SamplingOptions next = options;
  next.seed = 12;
  const GptCondition none_1 = none.select(row);
  EXPECT_TRUE(torch::equal(both[1], gpt::sample_codes(*model_, condition_.select(row), &none_1, {}, length, next)[0]));
  next.seed = 99;
  EXPECT_FALSE(torch::equal(both[1], gpt::sample_codes(*model_, condition_.select(row), &none_1, {}, length, next)[0]));
  // Without a length: ends at the end code or at max_steps.
  gpt::SequenceLength open;
  open.max_steps = 9;
  for (const at::Tensor& codes : gpt::sample_codes(*model_, condition_, &none, codes_.narrow(1, 0, 2), open, options)) {
    EXPECT_GE(codes.size(0), open.min_steps);
    EXPECT_LE(codes.size(0), 9);
  }
}

TEST(GptTokenSet, StoredTokensReadBackAndDamageIsFound) {
  gpt::TokenSet set;
  set.layers = 2;
  set.codebook_size = 8;
  set.cache_key = 11;
  set.tokenizer_key = 22;
  set.clips = {3, 7};
  set.steps = {2, 1};
  set.offsets = {0, 4};
  set.codes = {1, 2, 3, 4, 7, 0};
  const std::string bytes = gpt::serialize(set);
  const gpt::TokenSet back = gpt::deserialize_token_set(bytes, "t.bin");
  EXPECT_EQ(back.clips, set.clips);
  EXPECT_EQ(back.steps, set.steps);
  EXPECT_EQ(back.offsets, set.offsets);
  EXPECT_EQ(back.codes, set.codes);
  EXPECT_EQ(back.cache_key, 11u);
  EXPECT_EQ(back.tokenizer_key, 22u);
  EXPECT_EQ(back.codes_of(1)[1], 0);
  EXPECT_THROW(gpt::deserialize_token_set(bytes.substr(0, bytes.size() - 1), "t.bin"), InputError);
  EXPECT_THROW(gpt::deserialize_token_set(bytes + "x", "t.bin"), InputError);
  std::string out_of_range = bytes;
  out_of_range[out_of_range.size() - 4] = 9;  // the last code, beyond the codebook of 8
  try {
    gpt::deserialize_token_set(out_of_range, "t.bin");
    ADD_FAILURE() << "a code out of range was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("t.bin: the token set is damaged"), std::string::npos) << e.what();
  }
}

// Two captions, two token sequences of different lengths (layer 1 = layer 0 + 1, layer 2 = layer 0 + 2, mod K):
// a GPT trained on them writes each sequence for its caption and ends it on time.
TEST(GptLearning, ATinyGptLearnsWhichSequenceEachCaptionMeans) {
  torch::manual_seed(5);
  GptConfig config = tiny_config();
  TokenGpt model(config);
  model->train();
  const std::vector<std::vector<int64_t>> sequences = {{1, 2, 3, 4, 1, 2}, {5, 5, 6, 6}};
  const std::vector<std::vector<int64_t>> captions = {{2, 3, 4}, {7, 8}};
  const int64_t k = config.codebook_size, r = config.codebook_layers;
  at::Tensor inputs = torch::zeros({2, 6, r}, torch::kInt64);
  at::Tensor targets = torch::full({2, 7, r}, -1, torch::kInt64);
  for (int64_t i = 0; i < 2; ++i) {
    const auto& s = sequences[static_cast<size_t>(i)];
    for (size_t t = 0; t < s.size(); ++t) {
      for (int64_t layer = 0; layer < r; ++layer) {
        inputs[i][static_cast<int64_t>(t)][layer] = (s[t] + layer) % k;
        targets[i][static_cast<int64_t>(t)][layer] = (s[t] + layer) % k;
      }
    }
    targets[i][static_cast<int64_t>(s.size())][0] = k;
  }
  const at::Tensor skeleton = torch::zeros({2, gpt::skeleton_feature_width(4)});
  torch::optim::Adam adam(model->parameters(), torch::optim::AdamOptions(3e-3));
  double loss = 0;
  for (int step = 0; step < 150; ++step) {
    adam.zero_grad();
    const GptCondition c = model->condition(piece_batch(captions), skeleton, {});
    const at::Tensor l = gpt::gpt_loss(model->forward(c, inputs, targets), targets, 2).loss;
    l.backward();
    adam.step();
    loss = l.item<double>();
  }
  std::printf("final loss %.4f\n", loss);
  EXPECT_LT(loss, 0.05);
  model->eval();
  gpt::SamplingOptions greedy;
  greedy.top_k = 1;
  greedy.guidance = 1.0;
  gpt::SequenceLength open;
  open.min_steps = 1;
  open.max_steps = 10;
  const GptCondition c = model->condition(piece_batch(captions), skeleton, {});
  const std::vector<at::Tensor> drawn = gpt::sample_codes(*model, c, nullptr, {}, open, greedy);
  for (size_t i = 0; i < 2; ++i) {
    ASSERT_EQ(drawn[i].size(0), static_cast<int64_t>(sequences[i].size())) << "caption " << i;
    for (size_t t = 0; t < sequences[i].size(); ++t) {
      for (int64_t layer = 0; layer < r; ++layer) {
        EXPECT_EQ(drawn[i][static_cast<int64_t>(t)][layer].item<int64_t>(), (sequences[i][t] + layer) % k)
            << "caption " << i << " step " << t << " layer " << layer;
      }
    }
  }
}

}  // namespace
}  // namespace nec

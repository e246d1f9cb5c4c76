// TAT tokenizer: config, shapes of every kind, masking invariance, codes round
// trip, parameter budget, and learning on procedural zoo clips.
#include "nec/motion/features.h"
#include "nec/corpus/preprocess.h"
#include "nec/tat/loss.h"
#include "nec/tat/model_space.h"
#include "nec/tat/tokenizer.h"
#include "nec/tat/training.h"
#include "nec/zoo/creature.h"
#include "nec/zoo/motion_synthesis.h"
#include "tat_support.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace nec {
namespace {

using tat::BatchTensors;
using testing::make_batch;
using tat::TatConfig;
using tat::TokenizerKind;
using tat::TokenizerOutput;

constexpr TokenizerKind kAllKinds[] = {TokenizerKind::NecRvq, TokenizerKind::NecVq, TokenizerKind::ZeroPadRvq};

TatConfig small_config(TokenizerKind kind) {
  TatConfig config;
  config.kind = kind;
  config.joint_embedding_dim = 16;
  config.dim = 32;
  config.blocks = 2;
  config.attention_layers = 1;
  config.heads = 4;
  config.max_joints = 24;
  config.quantizer.layers = kind == TokenizerKind::NecVq ? 1 : 2;
  config.quantizer.codebook_size = 64;
  config.quantizer.code_dim = 32;
  return config;
}

int64_t parameter_count(torch::nn::Module& module) {
  int64_t count = 0;
  for (const at::Tensor& p : module.parameters()) count += p.numel();
  return count;
}

// Random clips on random skeletons of the given joint counts, T frames each.
struct RandomBatch {
  std::vector<Skeleton> skeletons;
  BatchTensors batch;
  at::Tensor embeddings;  // (B, J, 16)
};

RandomBatch random_batch(std::mt19937& rng, const std::vector<int>& joint_counts, int frames) {
  RandomBatch out;
  std::vector<Motion> motions;
  for (int joints : joint_counts) {
    out.skeletons.push_back(testing::random_skeleton(rng, joints));
    motions.push_back(testing::random_motion(rng, out.skeletons.back(), frames));
  }
  out.batch = make_batch(out.skeletons, motions);
  out.embeddings = torch::randn({out.batch.features.size(0), out.batch.features.size(2), 16}) *
                   out.batch.joint_mask.unsqueeze(-1);
  return out;
}

// A model of `kind` in eval mode, its codebooks seeded by a training-mode forward pass on x.
tat::Tokenizer seeded_model(TokenizerKind kind, const RandomBatch& x) {
  tat::Tokenizer model(small_config(kind));
  model->forward(x.batch.features, x.batch.joint_mask, x.batch.frame_mask,
                 kind == TokenizerKind::ZeroPadRvq ? at::Tensor() : x.embeddings);
  model->eval();
  return model;
}

TEST(TatTokenizer, KindNamesRoundTrip) {
  for (TokenizerKind kind : kAllKinds) EXPECT_EQ(tat::tokenizer_kind_from_string(tat::to_string(kind)), kind);
  EXPECT_EQ(tat::to_string(TokenizerKind::ZeroPadRvq), "zero-pad-rvq");
  EXPECT_THROW(tat::tokenizer_kind_from_string("nec"), std::invalid_argument);
}

TEST(TatTokenizer, ConfigValidation) {
  for (TokenizerKind kind : kAllKinds) EXPECT_NO_THROW(small_config(kind).validate());
  auto expect_bad = [](const TatConfig& config, const std::string& field) {
    try {
      config.validate();
      ADD_FAILURE() << "accepted a bad " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  TatConfig c = small_config(TokenizerKind::NecVq);
  c.quantizer.layers = 2;
  expect_bad(c, "quantizer.layers");
  c = small_config(TokenizerKind::ZeroPadRvq);
  c.max_joints = 0;
  expect_bad(c, "max_joints");
  c = small_config(TokenizerKind::NecRvq);
  c.heads = 5;
  expect_bad(c, "heads");
  c = small_config(TokenizerKind::NecRvq);
  c.blocks = 0;
  expect_bad(c, "blocks");
  c = small_config(TokenizerKind::NecRvq);
  c.quantizer.codebook_size = 0;
  expect_bad(c, "codebook_size");
  EXPECT_NE(small_config(TokenizerKind::NecRvq).to_string().find("kind=nec-rvq"), std::string::npos);
}

TEST(TatTokenizer, ShapesOfEveryKind) {
  torch::manual_seed(0);
  std::mt19937 rng(1);
  const RandomBatch x = random_batch(rng, {7, 4}, 16);
  for (TokenizerKind kind : kAllKinds) {
    const TatConfig config = small_config(kind);
    tat::Tokenizer model(config);
    const at::Tensor embeddings = kind == TokenizerKind::ZeroPadRvq ? at::Tensor() : x.embeddings;
    const TokenizerOutput out = model->forward(x.batch.features, x.batch.joint_mask, x.batch.frame_mask, embeddings);
    const int64_t layers = config.quantizer.layers;
    EXPECT_EQ(out.reconstruction.sizes(), (std::vector<int64_t>{2, 16, 7, 9})) << tat::to_string(kind);
    EXPECT_EQ(out.codes.sizes(), (std::vector<int64_t>{2, 4, layers}));
    EXPECT_EQ(out.codes.scalar_type(), torch::kLong);
    EXPECT_EQ(out.commitment_loss.dim(), 0);
    EXPECT_EQ(out.perplexity.sizes(), (std::vector<int64_t>{layers}));
    EXPECT_TRUE(torch::isfinite(out.reconstruction).all().item<bool>());
    // Padded joints are zero.
    EXPECT_EQ(out.reconstruction[1].narrow(1, 4, 3).abs().sum().item<double>(), 0.0);

    const at::Tensor latent = model->encode(x.batch.features, x.batch.joint_mask, embeddings);
    EXPECT_EQ(latent.sizes(), (std::vector<int64_t>{2, 4, config.quantizer.code_dim}));
    // T not a multiple of r = 4.
    try {
      model->encode(x.batch.features.narrow(1, 0, 14), x.batch.joint_mask, embeddings);
      ADD_FAILURE() << "accepted T = 14";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("multiple"), std::string::npos) << e.what();
    }
  }
}

TEST(TatTokenizer, ZeroPadRejectsTooManyJoints) {
  tat::Tokenizer model(small_config(TokenizerKind::ZeroPadRvq));
  std::mt19937 rng(2);
  const RandomBatch x = random_batch(rng, {30}, 8);
  try {
    model->encode(x.batch.features, x.batch.joint_mask, {});
    ADD_FAILURE() << "accepted 30 joints with max_joints 24";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("30"), std::string::npos) << message;
    EXPECT_NE(message.find("24"), std::string::npos) << message;
  }
}

TEST(TatTokenizer, NecNeedsJointEmbeddings) {
  tat::Tokenizer model(small_config(TokenizerKind::NecRvq));
  std::mt19937 rng(3);
  const RandomBatch x = random_batch(rng, {5}, 8);
  EXPECT_THROW(model->encode(x.batch.features, x.batch.joint_mask, {}), std::invalid_argument);
  EXPECT_THROW(model->encode(x.batch.features, x.batch.joint_mask, torch::zeros({1, 5, 8})), std::invalid_argument);
}

// A skeleton's reconstruction must not depend on what it is batched with, nor
// on the content of padded joints.
TEST(TatTokenizer, MaskingInvariance) {
  torch::manual_seed(4);
  std::mt19937 rng(4);
  const RandomBatch pair = random_batch(rng, {5, 11}, 16);
  for (TokenizerKind kind : kAllKinds) {
    tat::Tokenizer model = seeded_model(kind, pair);
    const bool nec = kind != TokenizerKind::ZeroPadRvq;
    torch::NoGradGuard no_grad;

    const at::Tensor alone_features = pair.batch.features.narrow(0, 0, 1).narrow(2, 0, 5).contiguous();
    const at::Tensor alone_mask = pair.batch.joint_mask.narrow(0, 0, 1).narrow(1, 0, 5).contiguous();
    const at::Tensor alone_embeddings = nec ? pair.embeddings.narrow(0, 0, 1).narrow(1, 0, 5).contiguous() : at::Tensor();
    const TokenizerOutput alone =
        model->forward(alone_features, alone_mask, pair.batch.frame_mask.narrow(0, 0, 1), alone_embeddings);

    // Garbage in item 0's padded joints (features and embeddings).
    at::Tensor features = pair.batch.features.clone();
    features[0].narrow(1, 5, 6).normal_(0.0, 3.0);
    at::Tensor embeddings = nec ? pair.embeddings.clone() : at::Tensor();
    if (nec) embeddings[0].narrow(0, 5, 6).normal_(0.0, 3.0);
    const TokenizerOutput batched = model->forward(features, pair.batch.joint_mask, pair.batch.frame_mask, embeddings);

    const double difference =
        (batched.reconstruction[0].narrow(1, 0, 5) - alone.reconstruction[0]).abs().max().item<double>();
    std::printf("%s: max difference alone vs batched with padding garbage %.3g\n", tat::to_string(kind).c_str(),
                difference);
    EXPECT_LT(difference, 1e-5) << tat::to_string(kind);
    // Codes may differ between equal codebook entries (seeding draws rows with replacement): compare their vectors.
    const double latent_difference =
        (model->codes_to_latent(batched.codes.narrow(0, 0, 1)) - model->codes_to_latent(alone.codes)).abs().max().item<double>();
    EXPECT_LT(latent_difference, 1e-6) << tat::to_string(kind);
  }
}

TEST(TatTokenizer, NecReadsWhatTellsASkeletonsJointsApart) {
  // Only the differences between one skeleton's joint embeddings count: a part shared by all its joints, or
  // their overall scale, changes nothing; one joint's own embedding does.
  torch::manual_seed(6);
  std::mt19937 rng(6);
  const RandomBatch pair = random_batch(rng, {5, 11}, 16);
  for (TokenizerKind kind : {TokenizerKind::NecRvq, TokenizerKind::NecVq}) {
    tat::Tokenizer model = seeded_model(kind, pair);
    torch::NoGradGuard no_grad;
    const auto reconstruct = [&](const at::Tensor& embeddings) {
      return model->forward(pair.batch.features, pair.batch.joint_mask, pair.batch.frame_mask, embeddings)
          .reconstruction;
    };
    const at::Tensor reference = reconstruct(pair.embeddings);
    // Item 0 shifted by a common vector on its real joints and scaled by 3; item 1 scaled by 0.5.
    at::Tensor moved = pair.embeddings.clone();
    moved[0].narrow(0, 0, 5).add_(torch::randn({1, 16}) * 4.0).mul_(3.0);
    moved[1].mul_(0.5);
    EXPECT_LT((reconstruct(moved) - reference).abs().max().item<double>(), 1e-4) << tat::to_string(kind);
    at::Tensor one_joint = pair.embeddings.clone();
    one_joint[1][3].add_(torch::randn({16}));
    EXPECT_GT((reconstruct(one_joint)[1] - reference[1]).abs().max().item<double>(), 1e-3) << tat::to_string(kind);
  }
}

TEST(TatTokenizer, NecDecodesTheSamePathOnEverySkeleton) {
  // The root's horizontal path comes from the tokens alone: one latent decoded onto a 5-joint and an 11-joint
  // skeleton moves both roots alike (Δx, Δz in body sizes), while the poses and the root's height differ.
  torch::manual_seed(8);
  std::mt19937 rng(8);
  const RandomBatch pair = random_batch(rng, {5, 11}, 16);
  for (TokenizerKind kind : {TokenizerKind::NecRvq, TokenizerKind::NecVq}) {
    tat::Tokenizer model = seeded_model(kind, pair);
    torch::NoGradGuard no_grad;
    const at::Tensor latent = model->encode(pair.batch.features.narrow(0, 0, 1).narrow(2, 0, 5),
                                            pair.batch.joint_mask.narrow(0, 0, 1).narrow(1, 0, 5),
                                            pair.embeddings.narrow(0, 0, 1).narrow(1, 0, 5));
    const at::Tensor quantized = model->quantize(latent).quantized;
    const auto decode_onto = [&](int64_t item, int64_t joints) {
      return model->decode(quantized, pair.batch.joint_mask.narrow(0, item, 1).narrow(1, 0, joints),
                           pair.embeddings.narrow(0, item, 1).narrow(1, 0, joints).contiguous(), torch::zeros({1}));
    };
    const at::Tensor small = decode_onto(0, 5), large = decode_onto(1, 11);
    const at::Tensor small_root = small.select(2, 0), large_root = large.select(2, 0);
    for (int64_t channel : {0, 2}) {
      EXPECT_LT((small_root.select(-1, channel) - large_root.select(-1, channel)).abs().max().item<double>(), 1e-6)
          << tat::to_string(kind) << " channel " << channel;
    }
    EXPECT_GT(small_root.select(-1, 0).abs().max().item<double>(), 1e-4) << tat::to_string(kind);
    EXPECT_GT((small_root.select(-1, 1) - large_root.select(-1, 1)).abs().max().item<double>(), 1e-4);
    EXPECT_GT((small.narrow(2, 1, 4) - large.narrow(2, 1, 4)).abs().max().item<double>(), 1e-3);
  }
}

TEST(TatTokenizer, DecodingTheCodesGivesTheReconstruction) {
  torch::manual_seed(5);
  std::mt19937 rng(5);
  const RandomBatch x = random_batch(rng, {6, 9}, 16);
  for (TokenizerKind kind : kAllKinds) {
    tat::Tokenizer model = seeded_model(kind, x);
    const at::Tensor embeddings = kind == TokenizerKind::ZeroPadRvq ? at::Tensor() : x.embeddings;
    torch::NoGradGuard no_grad;
    const TokenizerOutput out = model->forward(x.batch.features, x.batch.joint_mask, x.batch.frame_mask, embeddings);
    const at::Tensor latent = model->codes_to_latent(out.codes);
    const at::Tensor decoded = model->decode(latent, x.batch.joint_mask, embeddings, tat::start_heading(x.batch.features));
    const double difference = (decoded - out.reconstruction).abs().max().item<double>();
    EXPECT_LT(difference, 1e-5) << tat::to_string(kind);
    // encode -> quantize gives the same codes.
    const at::Tensor step_mask = x.batch.frame_mask.view({2, 4, 4}).any(-1);
    const tat::QuantizerOutput q =
        model->quantize(model->encode(x.batch.features, x.batch.joint_mask, embeddings), step_mask);
    EXPECT_TRUE(torch::equal(q.codes, out.codes));
    EXPECT_EQ(q.quantized.sizes(), latent.sizes());
  }
}

TEST(TatTokenizer, EveryParameterGetsAGradient) {
  torch::manual_seed(6);
  std::mt19937 rng(6);
  const RandomBatch x = random_batch(rng, {6, 9}, 16);
  for (TokenizerKind kind : kAllKinds) {
    tat::Tokenizer model(small_config(kind));
    const at::Tensor embeddings = kind == TokenizerKind::ZeroPadRvq ? at::Tensor() : x.embeddings;
    const TokenizerOutput out = model->forward(x.batch.features, x.batch.joint_mask, x.batch.frame_mask, embeddings);
    tat::reconstruction_loss(out.reconstruction, x.batch, out.commitment_loss, {}).total.backward();
    for (const auto& p : model->named_parameters()) {
      ASSERT_TRUE(p.value().grad().defined()) << tat::to_string(kind) << " " << p.key();
      EXPECT_GT(p.value().grad().abs().sum().item<double>(), 0.0) << tat::to_string(kind) << " " << p.key();
    }
  }
}

TEST(TatTokenizer, ItemsPerPartKeepsEachPassWithinTheBudget) {
  EXPECT_EQ(tat::items_per_part(8, 100, 0), 8);     // no limit: one pass
  EXPECT_EQ(tat::items_per_part(8, 100, 350), 3);   // 3 × 100 <= 350 < 4 × 100
  EXPECT_EQ(tat::items_per_part(8, 100, 50), 1);    // one item is the least
  EXPECT_EQ(tat::items_per_part(8, 100, 5000), 8);  // never more than the batch
}

// Gradients of a batch run in parts add up to those of the whole batch (eval
// mode: no codebook updates between the parts; equal masks: equal shares).
TEST(TatTokenizer, BackwardInPartsGivesTheWholeBatchGradients) {
  std::mt19937 rng(8);
  const RandomBatch x = random_batch(rng, {7, 7, 7, 7}, 16);
  for (TokenizerKind kind : kAllKinds) {
    const at::Tensor embeddings = kind == TokenizerKind::ZeroPadRvq ? at::Tensor() : x.embeddings;
    auto gradients_and_loss = [&](int64_t max_joint_frames) {
      torch::manual_seed(8);
      tat::Tokenizer model(small_config(kind));
      model->eval();
      const tat::LossTerms terms = tat::backward_in_parts(model, x.batch, embeddings, {}, max_joint_frames);
      std::vector<at::Tensor> gradients;
      for (const at::Tensor& p : model->parameters()) gradients.push_back(p.grad().clone());
      return std::make_pair(gradients, terms.at("loss"));
    };
    const auto [whole, whole_loss] = gradients_and_loss(0);
    const auto [parts, parts_loss] = gradients_and_loss(16 * 7);  // one item per pass
    EXPECT_NEAR(parts_loss, whole_loss, 1e-5 * std::abs(whole_loss)) << tat::to_string(kind);
    ASSERT_EQ(parts.size(), whole.size());
    // Measured against each parameter's largest gradient: summation order differs between the passes, and
    // float rounding through attention reaches ~7e-4 of it on some CPUs; a wrong share would be >= 1/4.
    for (size_t i = 0; i < whole.size(); ++i) {
      const double difference = (parts[i] - whole[i]).abs().max().item<double>();
      const double largest = whole[i].abs().max().item<double>();
      EXPECT_LE(difference, 5e-3 * largest + 1e-7)
          << tat::to_string(kind) << " parameter " << i << ": max difference " << difference
          << ", largest gradient " << largest;
    }
  }
}

TEST(TatTokenizer, ParameterBudgetsAreComparable) {
  TatConfig config;  // dim 128, code_dim 128, K 256, R 4, blocks 2, attention_layers 1, joint_embedding_dim 128
  config.max_joints = 64;
  config.kind = TokenizerKind::NecRvq;
  tat::Tokenizer nec(config);
  config.kind = TokenizerKind::ZeroPadRvq;
  tat::Tokenizer padded(config);
  const int64_t nec_count = parameter_count(*nec), padded_count = parameter_count(*padded);
  std::printf("parameters: nec-rvq %lld, zero-pad-rvq %lld (max_joints 64)\n", static_cast<long long>(nec_count),
              static_cast<long long>(padded_count));
  const double ratio = static_cast<double>(nec_count) / static_cast<double>(padded_count);
  EXPECT_GT(ratio, 0.75);
  EXPECT_LT(ratio, 1.33);
}

// Eight zoo clips of different body plans, preprocessed, 32 frames each.
struct ZooBatch {
  BatchTensors batch;
  at::Tensor embeddings;  // (B, J, 16), fixed random joint identities
};

constexpr int kZooFrames = 16;

ZooBatch zoo_batch() {
  const zoo::BodyPlan plans[] = {zoo::BodyPlan::Biped, zoo::BodyPlan::Quadruped, zoo::BodyPlan::Hexapod,
                                 zoo::BodyPlan::Spider, zoo::BodyPlan::Snake,    zoo::BodyPlan::Bird,
                                 zoo::BodyPlan::Fish,  zoo::BodyPlan::Biped};
  std::vector<Skeleton> skeletons;
  std::vector<Motion> motions;
  for (size_t i = 0; i < std::size(plans); ++i) {
    const zoo::Creature creature = zoo::make_creature(plans[i], 100 + i);
    const std::vector<zoo::Action> actions = zoo::supported_actions(plans[i]);
    zoo::MotionSpec spec;
    spec.action = actions[(i * 3 + 1) % actions.size()];
    spec.seconds = 1.2;
    spec.seed = i;
    const zoo::SynthesizedMotion motion = zoo::synthesize_motion(creature, spec);
    const PreparedClip prepared = preprocess(Clip{creature.skeleton, motion.motion, {}}, "zoo");
    EXPECT_TRUE(prepared.report.accepted()) << prepared.report.rejection;
    skeletons.push_back(prepared.clip.skeleton);
    motions.push_back(prepared.clip.motion.slice(0, kZooFrames));
  }
  ZooBatch out;
  out.batch = make_batch(skeletons, motions);
  out.embeddings = torch::randn({out.batch.features.size(0), out.batch.features.size(2), 16});
  return out;
}

TEST(TatTokenizer, LearnsToReconstructZooClips) {
  torch::set_num_threads(1);
  torch::manual_seed(7);
  const ZooBatch x = zoo_batch();
  std::printf("zoo batch: %lld clips, %lld frames, up to %lld joints\n", static_cast<long long>(x.batch.features.size(0)),
              static_cast<long long>(x.batch.features.size(1)), static_cast<long long>(x.batch.features.size(2)));
  tat::Tokenizer model(small_config(TokenizerKind::NecRvq));
  torch::optim::Adam optimizer(model->parameters(), torch::optim::AdamOptions(3e-3));
  auto evaluate = [&] {
    torch::NoGradGuard no_grad;
    model->eval();
    const TokenizerOutput out = model->forward(x.batch.features, x.batch.joint_mask, x.batch.frame_mask, x.embeddings);
    const tat::ReconstructionLoss l = tat::reconstruction_loss(out.reconstruction, x.batch, out.commitment_loss, {});
    model->train();
    return l.total.item<double>() - l.commitment;
  };
  const auto start = std::chrono::steady_clock::now();
  model->forward(x.batch.features, x.batch.joint_mask, x.batch.frame_mask, x.embeddings);  // seeds the codebooks
  model->update_codebooks();
  const double initial = evaluate();
  const int steps = 80;
  for (int step = 0; step < steps; ++step) {
    const TokenizerOutput out = model->forward(x.batch.features, x.batch.joint_mask, x.batch.frame_mask, x.embeddings);
    const tat::ReconstructionLoss l = tat::reconstruction_loss(out.reconstruction, x.batch, out.commitment_loss, {});
    optimizer.zero_grad();
    l.total.backward();
    optimizer.step();
    model->update_codebooks();
  }
  const double final_loss = evaluate();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("reconstruction loss (eval): %.4f -> %.4f (x%.3f) after %d Adam steps in %.1f s\n", initial, final_loss,
              final_loss / initial, steps, seconds);
  EXPECT_LT(final_loss, 0.5 * initial);
}

}  // namespace
}  // namespace nec

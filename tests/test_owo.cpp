// OwO skeleton graph: featurization, encoder invariances, pretraining.
#include "nec/owo/encoder.h"
#include "nec/owo/graph.h"
#include "nec/owo/pretrain.h"
#include "nec/zoo/creature.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace nec {
namespace {

using owo::GraphBatch;
using owo::SkeletonGraph;

// One intra-op thread: these tensors are small, and ctest runs test programs
// side by side on two cores, where two OpenMP threads per program spin against
// each other (ItLearns measured 50 s with 2 threads under load, 10 s with 1).
constexpr int kTorchThreads = 1;

// 0 root -> 1 spine -> {2 head, 3 arm -> 4 hand}; 0 root -> 5 tail.
// Diameter 4 (root, spine 2, arm 1, hand 1).
Skeleton small_tree() {
  Skeleton s;
  const ChannelLayout layout = ChannelLayout::rotations(EulerOrder::ZXY);
  s.add_joint("root", -1, Vec3(0, 100, 0), ChannelLayout::position_rotations(EulerOrder::ZXY));
  s.add_joint("spine", 0, Vec3(0, 2, 0), layout);
  s.add_joint("head", 1, Vec3(0, 1, 0), layout);
  s.add_joint("arm", 1, Vec3(1, 0, 0), layout);
  s.add_joint("hand", 3, Vec3(1, 0, 0), layout);
  s.add_joint("tail", 0, Vec3(0, 0, -1), layout);
  return s;
}

// Up to `count` zoo skeletons of at most `max_joints` joints, cycling over body plans.
std::vector<Skeleton> zoo_skeletons(int count, int max_joints) {
  std::vector<Skeleton> out;
  for (uint64_t seed = 0; static_cast<int>(out.size()) < count && seed < 200; ++seed) {
    for (zoo::BodyPlan plan : zoo::kAllBodyPlans) {
      Skeleton skeleton = zoo::make_creature(plan, seed).skeleton;
      if (skeleton.joint_count() <= max_joints && static_cast<int>(out.size()) < count) {
        out.push_back(std::move(skeleton));
      }
    }
  }
  return out;
}

owo::OwoConfig tiny_config() {
  owo::OwoConfig config;
  config.dim = 32;
  config.layers = 2;
  config.heads = 4;
  config.edge_dim = 16;
  return config;
}

double max_abs_diff(const torch::Tensor& a, const torch::Tensor& b) { return (a - b).abs().max().item<double>(); }

TEST(OwoGraph, SmallTreeFeatures) {
  const SkeletonGraph g = owo::make_skeleton_graph(small_tree());
  ASSERT_EQ(g.joint_count, 6);
  EXPECT_EQ(g.depths.sizes(), (std::vector<int64_t>{6}));
  const std::vector<int64_t> depths = {0, 1, 2, 2, 3, 1};
  const std::vector<int64_t> parents = {-1, 0, 1, 1, 3, 0};
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(g.depths[j].item<int64_t>(), depths[j]) << "joint " << j;
    EXPECT_EQ(g.parents[j].item<int64_t>(), parents[j]) << "joint " << j;
  }
  // Full LCA matrix, symmetric, checked against a hand-written one.
  const int64_t expected_lca[6][6] = {{0, 0, 0, 0, 0, 0}, {0, 1, 1, 1, 1, 0}, {0, 1, 2, 1, 1, 0},
                                      {0, 1, 1, 3, 3, 0}, {0, 1, 1, 3, 4, 0}, {0, 0, 0, 0, 0, 5}};
  const int64_t expected_distance[6][6] = {{0, 1, 2, 2, 3, 1}, {1, 0, 1, 1, 2, 2}, {2, 1, 0, 2, 3, 3},
                                           {2, 1, 2, 0, 1, 3}, {3, 2, 3, 1, 0, 4}, {1, 2, 3, 3, 4, 0}};
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      EXPECT_EQ(g.lca[i][j].item<int64_t>(), expected_lca[i][j]) << i << ", " << j;
      EXPECT_EQ(g.tree_distance[i][j].item<int64_t>(), expected_distance[i][j]) << i << ", " << j;
    }
  }
  // Geometry divided by the diameter (4); the root's world offset dropped.
  const float tolerance = 1e-6f;
  EXPECT_NEAR(g.rest_offsets[0].abs().sum().item<float>(), 0.0f, tolerance);
  EXPECT_NEAR(g.rest_positions[4][0].item<float>(), 0.5f, tolerance);
  EXPECT_NEAR(g.rest_positions[4][1].item<float>(), 0.5f, tolerance);
  EXPECT_NEAR(g.rest_positions[5][2].item<float>(), -0.25f, tolerance);
  // Node geometry: offset, bone length, depth * 0.1, children * 0.25, leaf.
  EXPECT_NEAR(g.node_geometry[1][1].item<float>(), 0.5f, tolerance);
  EXPECT_NEAR(g.node_geometry[1][3].item<float>(), 0.5f, tolerance);
  EXPECT_NEAR(g.node_geometry[4][4].item<float>(), 0.3f, tolerance);
  EXPECT_NEAR(g.node_geometry[1][5].item<float>(), 0.5f, tolerance);
  EXPECT_EQ(g.node_geometry[1][6].item<float>(), 0.0f);
  EXPECT_EQ(g.node_geometry[2][6].item<float>(), 1.0f);
  // Edge 2 -> 4: relative x = 0.5, sin(pi * 0.5) = 1, relation Other.
  const owo::GraphOptions options;
  const int width = owo::edge_feature_width(options);
  ASSERT_EQ(g.edge_features.sizes(), (std::vector<int64_t>{6, 6, width}));
  EXPECT_NEAR(g.edge_features[2][4][0].item<float>(), 0.5f, tolerance);
  EXPECT_NEAR(g.edge_features[2][4][1].item<float>(), 1.0f, tolerance);
  const int relation_start = width - owo::kJointRelationCount;
  EXPECT_NEAR(g.edge_features[2][4][relation_start - 1].item<float>(), 3.0f / options.max_tree_distance, tolerance);
  auto relation_of = [&](int i, int j) {
    return g.edge_features[i][j].narrow(0, relation_start, owo::kJointRelationCount).argmax().item<int64_t>();
  };
  EXPECT_EQ(relation_of(3, 3), static_cast<int64_t>(owo::JointRelation::Self));
  EXPECT_EQ(relation_of(1, 3), static_cast<int64_t>(owo::JointRelation::Parent));
  EXPECT_EQ(relation_of(3, 1), static_cast<int64_t>(owo::JointRelation::Child));
  EXPECT_EQ(relation_of(1, 4), static_cast<int64_t>(owo::JointRelation::Ancestor));
  EXPECT_EQ(relation_of(4, 0), static_cast<int64_t>(owo::JointRelation::Descendant));
  EXPECT_EQ(relation_of(2, 4), static_cast<int64_t>(owo::JointRelation::Other));
  EXPECT_EQ(g.edge_features[2][4].narrow(0, relation_start, owo::kJointRelationCount).sum().item<float>(), 1.0f);
}

TEST(OwoGraph, ScaleInvariantWhenNormalized) {
  Skeleton big = small_tree();
  for (Vec3& offset : big.offsets) offset *= 100.0;
  const SkeletonGraph a = owo::make_skeleton_graph(small_tree());
  const SkeletonGraph b = owo::make_skeleton_graph(big);
  const double diff = max_abs_diff(a.edge_features, b.edge_features);
  EXPECT_LT(diff, 1e-5) << "max diff " << diff;
}

TEST(OwoGraph, RejectsMismatchedNames) {
  EXPECT_THROW(owo::make_skeleton_graph(small_tree(), torch::zeros({5, 8})), std::invalid_argument);
  const SkeletonGraph named = owo::make_skeleton_graph(small_tree(), torch::ones({6, 8}));
  EXPECT_THROW(owo::collate({named}, 4), std::invalid_argument);
  EXPECT_THROW(owo::collate({}, 4), std::invalid_argument);
}

TEST(OwoGraph, CollatePadsAndMasks) {
  const std::vector<Skeleton> zoo = zoo_skeletons(1, 100);
  const SkeletonGraph small = owo::make_skeleton_graph(small_tree(), torch::ones({6, 4}));
  const SkeletonGraph large = owo::make_skeleton_graph(zoo[0]);
  const int64_t jmax = large.joint_count;
  ASSERT_GT(jmax, 6);
  const GraphBatch batch = owo::collate({small, large}, 4);
  EXPECT_EQ(batch.size(), 2);
  EXPECT_EQ(batch.max_joints(), jmax);
  EXPECT_EQ(batch.joint_mask.sizes(), (std::vector<int64_t>{2, jmax}));
  EXPECT_EQ(batch.joint_mask[0].sum().item<int64_t>(), 6);
  EXPECT_EQ(batch.joint_mask[1].sum().item<int64_t>(), jmax);
  EXPECT_TRUE(batch.joint_mask[0][5].item<bool>());
  EXPECT_FALSE(batch.joint_mask[0][6].item<bool>());
  EXPECT_TRUE(batch.has_names[0].item<bool>());
  EXPECT_FALSE(batch.has_names[1].item<bool>());
  EXPECT_EQ(batch.name_embeddings.sizes(), (std::vector<int64_t>{2, jmax, 4}));
  EXPECT_EQ(batch.name_embeddings[1].abs().sum().item<float>(), 0.0f);
  EXPECT_EQ(batch.name_embeddings[0][5][0].item<float>(), 1.0f);
  EXPECT_EQ(batch.name_embeddings[0][6][0].item<float>(), 0.0f);
  EXPECT_EQ(batch.parents[0][6].item<int64_t>(), -1);
  EXPECT_EQ(batch.lca[0][6][0].item<int64_t>(), -1);
  EXPECT_EQ(batch.lca[0][4][2].item<int64_t>(), 1);
  EXPECT_EQ(batch.edge_features[0].narrow(0, 6, jmax - 6).abs().sum().item<float>(), 0.0f);
  EXPECT_EQ(max_abs_diff(batch.edge_features[0].narrow(0, 0, 6).narrow(1, 0, 6), small.edge_features), 0.0);
  EXPECT_EQ(max_abs_diff(batch.lca[1], large.lca), 0.0);
}

TEST(OwoEncoder, ShapesAndPaddingInvariance) {
  torch::set_num_threads(kTorchThreads);
  const std::vector<Skeleton> zoo = zoo_skeletons(1, 100);
  const SkeletonGraph small = owo::make_skeleton_graph(small_tree());
  const SkeletonGraph large = owo::make_skeleton_graph(zoo[0]);
  for (bool tree_only : {false, true}) {
    torch::manual_seed(3);
    owo::OwoConfig config = tiny_config();
    config.tree_edges_only = tree_only;
    owo::OwoEncoder encoder(config);
    encoder->eval();
    torch::NoGradGuard no_grad;
    const owo::OwoOutput alone = encoder->forward(owo::collate({small}, 0));
    const owo::OwoOutput padded = encoder->forward(owo::collate({small, large}, 0));
    EXPECT_EQ(alone.joints.sizes(), (std::vector<int64_t>{1, 6, 32}));
    EXPECT_EQ(alone.skeleton.sizes(), (std::vector<int64_t>{1, 32}));
    EXPECT_EQ(padded.joints.sizes(), (std::vector<int64_t>{2, large.joint_count, 32}));
    EXPECT_EQ(padded.skeleton.sizes(), (std::vector<int64_t>{2, 32}));
    const double joint_diff = max_abs_diff(alone.joints[0], padded.joints[0].narrow(0, 0, 6));
    const double skeleton_diff = max_abs_diff(alone.skeleton[0], padded.skeleton[0]);
    std::printf("tree_edges_only=%d: padding max diff joints %.3g, skeleton %.3g\n", tree_only, joint_diff,
                skeleton_diff);
    EXPECT_LT(joint_diff, 1e-5);
    EXPECT_LT(skeleton_diff, 1e-5);
    EXPECT_EQ(padded.joints[0].narrow(0, 6, large.joint_count - 6).abs().sum().item<float>(), 0.0f);
    EXPECT_TRUE(torch::isfinite(padded.joints).all().item<bool>());
    // The same skeleton twice gives the same output, and so does a second call.
    const owo::OwoOutput twice = encoder->forward(owo::collate({small, small}, 0));
    EXPECT_LT(max_abs_diff(twice.joints[0], twice.joints[1]), 1e-6);
    EXPECT_LT(max_abs_diff(encoder->forward(owo::collate({small}, 0)).joints, alone.joints), 1e-6);
  }
}

TEST(OwoEncoder, RejectsWrongNameWidth) {
  owo::OwoConfig config = tiny_config();
  config.name_dim = 8;
  owo::OwoEncoder encoder(config);
  EXPECT_THROW(encoder->forward(owo::collate({owo::make_skeleton_graph(small_tree())}, 4)), std::invalid_argument);
  owo::OwoConfig bad = tiny_config();
  bad.heads = 5;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(OwoPretrain, GradientsReachEveryParameter) {
  torch::set_num_threads(kTorchThreads);
  torch::manual_seed(5);
  owo::OwoConfig config = tiny_config();
  config.name_dim = 8;
  owo::OwoPretrainer model(config, owo::PretrainConfig{});
  const std::vector<Skeleton> zoo = zoo_skeletons(2, 40);
  std::vector<SkeletonGraph> graphs;
  for (const Skeleton& s : zoo) graphs.push_back(owo::make_skeleton_graph(s, torch::randn({s.joint_count(), 8})));
  graphs.push_back(owo::make_skeleton_graph(small_tree()));  // no names
  const owo::PretrainLosses losses = model->backward(owo::collate(graphs, 8));
  ASSERT_TRUE(losses.offset && losses.pair_offset && losses.lca && losses.name && losses.lca_accuracy);
  EXPECT_TRUE(std::isfinite(losses.total));
  for (const auto& item : model->named_parameters()) {
    ASSERT_TRUE(item.value().grad().defined()) << item.key();
    const double norm = item.value().grad().norm().item<double>();
    EXPECT_TRUE(std::isfinite(norm)) << item.key();
    EXPECT_GT(norm, 0.0) << item.key();
  }
}

TEST(OwoPretrain, TermsFollowFlagsAndNames) {
  torch::manual_seed(6);
  owo::PretrainConfig flags;
  flags.pair_offset_loss = false;
  flags.lca_loss = false;
  owo::OwoConfig config = tiny_config();
  config.name_dim = 8;
  owo::OwoPretrainer model(config, flags);
  const owo::PretrainLosses unnamed = model->evaluate(owo::collate({owo::make_skeleton_graph(small_tree())}, 8));
  EXPECT_TRUE(unnamed.offset.has_value());
  EXPECT_FALSE(unnamed.pair_offset.has_value());
  EXPECT_FALSE(unnamed.lca.has_value());
  EXPECT_FALSE(unnamed.lca_accuracy.has_value());
  EXPECT_FALSE(unnamed.name.has_value());  // no embeddings: skipped
  EXPECT_NEAR(unnamed.total, *unnamed.offset, 1e-6);
  const owo::PretrainLosses named =
      model->evaluate(owo::collate({owo::make_skeleton_graph(small_tree(), torch::randn({6, 8}))}, 8));
  ASSERT_TRUE(named.name.has_value());
  EXPECT_TRUE(std::isfinite(*named.name));
  owo::PretrainConfig none;
  none.offset_loss = none.pair_offset_loss = none.lca_loss = none.name_loss = false;
  EXPECT_THROW(none.validate(), std::invalid_argument);
}

// Pretrains a tiny encoder on zoo skeletons: LCA accuracy must beat both
// chance and, by 0.1, the "always the root" answer; the offset loss must halve.
TEST(OwoPretrain, ItLearns) {
  torch::set_num_threads(kTorchThreads);
  torch::manual_seed(7);
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Skeleton> zoo = zoo_skeletons(40, 48);
  ASSERT_EQ(zoo.size(), 40u);
  std::vector<SkeletonGraph> graphs;
  double chance = 0.0, root_share = 0.0;
  for (const Skeleton& s : zoo) {
    graphs.push_back(owo::make_skeleton_graph(s));
    const double j = s.joint_count();
    chance += 1.0 / j / zoo.size();
    root_share += (graphs.back().lca == 0).sum().item<double>() / (j * j) / zoo.size();
  }
  constexpr int kBatch = 8;
  std::vector<GraphBatch> batches;
  for (size_t first = 0; first < graphs.size(); first += kBatch) {
    batches.push_back(owo::collate({graphs.begin() + first, graphs.begin() + first + kBatch}, 0));
  }
  const GraphBatch all = owo::collate(graphs, 0);

  owo::PretrainConfig pretrain;
  pretrain.pairs_per_skeleton = 64;
  owo::OwoPretrainer model(tiny_config(), pretrain);
  torch::optim::AdamW optimizer(model->parameters(), torch::optim::AdamWOptions(3e-3).weight_decay(0.0));
  const owo::PretrainLosses before = model->evaluate(all);
  constexpr int kSteps = 150;
  for (int step = 0; step < kSteps; ++step) {
    optimizer.zero_grad();
    model->backward(batches[step % batches.size()]);
    optimizer.step();
  }
  const owo::PretrainLosses after = model->evaluate(all);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "ItLearns: %d steps in %.1f s; offset %.4f -> %.4f, pair offset %.4f -> %.4f, lca %.3f -> %.3f, "
      "lca accuracy %.3f -> %.3f (chance %.3f, always-root %.3f)\n",
      kSteps, seconds, *before.offset, *after.offset, *before.pair_offset, *after.pair_offset, *before.lca,
      *after.lca, *before.lca_accuracy, *after.lca_accuracy, chance, root_share);
  EXPECT_LT(*after.offset, 0.5 * *before.offset);
  EXPECT_GT(*after.lca_accuracy, 5.0 * chance);
  EXPECT_GT(*after.lca_accuracy, root_share + 0.1);
}

// A spine of `spine` joints (a chain, like a snake's), with a two-joint leg on
// each side of every `leg_every`-th spine joint (0: no legs).
Skeleton spine_with_legs(int spine, int leg_every) {
  Skeleton s;
  const ChannelLayout layout = ChannelLayout::rotations(EulerOrder::ZXY);
  s.add_joint("root", -1, Vec3(0, 1, 0), ChannelLayout::position_rotations(EulerOrder::ZXY));
  for (int n = 1; n < spine; ++n) s.add_joint("spine" + std::to_string(n), n - 1, Vec3(0, 0, -0.2), layout);
  for (int n = leg_every; leg_every > 0 && n < spine; n += leg_every) {
    for (double side : {-1.0, 1.0}) {
      const int hip = s.add_joint("hip" + std::to_string(s.joint_count()), n, Vec3(0.3 * side, 0, 0), layout);
      s.add_joint("foot" + std::to_string(s.joint_count()), hip, Vec3(0.1 * side, -0.4, 0), layout);
    }
  }
  return s;
}

// The LCA pointer on long chains: a tiny model trained on two long-spined
// skeletons must get every pair's LCA (the argmax over all joints) right on
// nearly all pairs. On a chain, the LCA of two joints is the shallower one,
// which a dot product between FFN(h_i + h_j) and key_k hardly expresses.
TEST(OwoPretrain, LcaPointerFitsLongChains) {
  torch::set_num_threads(kTorchThreads);
  torch::manual_seed(8);
  std::vector<SkeletonGraph> graphs = {owo::make_skeleton_graph(spine_with_legs(40, 0)),
                                       owo::make_skeleton_graph(spine_with_legs(30, 5))};
  const GraphBatch batch = owo::collate(graphs, 0);
  owo::PretrainConfig pretrain;
  pretrain.offset_loss = pretrain.pair_offset_loss = pretrain.name_loss = false;
  pretrain.pairs_per_skeleton = 256;
  owo::OwoPretrainer model(tiny_config(), pretrain);
  torch::optim::AdamW optimizer(model->parameters(), torch::optim::AdamWOptions(3e-3).weight_decay(0.0));
  constexpr int kSteps = 300;
  for (int step = 0; step < kSteps; ++step) {
    optimizer.zero_grad();
    model->backward(batch);
    optimizer.step();
  }
  const at::Tensor predicted = model->all_pair_lca_logits(batch).argmax(-1);  // (B, J, J)
  const at::Tensor pairs = batch.joint_mask.unsqueeze(2).logical_and(batch.joint_mask.unsqueeze(1));
  const double accuracy =
      (predicted == batch.lca).logical_and(pairs).sum().item<double>() / pairs.sum().item<double>();
  std::printf("LcaPointerFitsLongChains: all-pair LCA accuracy %.4f after %d steps\n", accuracy, kSteps);
  EXPECT_GT(accuracy, 0.99);
}

}  // namespace
}  // namespace nec

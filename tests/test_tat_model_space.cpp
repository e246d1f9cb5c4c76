// The tokenizer's model space against hand-built motions: round trip, body-frame
// displacement on rigs whose root faces away from the body, turning as a yaw rate.
#include "nec/motion/features.h"
#include "nec/tat/fk.h"
#include "nec/tat/model_space.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>

namespace nec {
namespace {

using tat::features_to_model_space;
using tat::kModelChannels;
using tat::kRootMotionScale;
using tat::model_space_to_features;

at::Tensor tensor_of(const Skeleton& s, const Motion& m) {
  Features f = encode_features(s, m);
  return torch::from_blob(f.data.data(), {1, f.frame_count, f.joint_count, 9}, torch::kFloat32).clone();
}

// Root heading (radians about +Y) of features (1, T, J, 9) at frame t.
double heading_at(const at::Tensor& features, int64_t t) {
  const at::Tensor h = tat::heading_matrix(tat::rot6d_to_matrix(features[0][t][0].narrow(0, 3, 6)));
  return std::atan2(h[0][2].item<double>(), h[0][0].item<double>());
}

double max_difference(const at::Tensor& a, const at::Tensor& b) { return (a - b).abs().max().item<double>(); }

// A walk that starts facing +Z and turns left at `rate` radians a frame; the
// root joint faces `offset` away from the body.
Motion turning_walk(const Motion& base, double rate, double offset) {
  Motion m = base;
  Vec3 position(0.3, 1.0, -0.2);
  for (int t = 0; t < m.frame_count; ++t) {
    const double body_heading = rate * t;
    position += Eigen::AngleAxisd(body_heading, Vec3::UnitY()) * Vec3(0.0, 0.01 * std::sin(t), 0.05);
    m.rotation(t, 0) = Quat(Eigen::AngleAxisd(body_heading + offset, Vec3::UnitY()) *
                            Eigen::AngleAxisd(0.2 * std::sin(0.5 * t), Vec3::UnitX()));  // some sway
    m.translation(t, 0) = position;
  }
  return m;
}

TEST(TatModelSpace, RoundTripsRandomClips) {
  std::mt19937 rng(3);
  for (int k = 0; k < 4; ++k) {
    const Skeleton s = testing::random_skeleton(rng, 6);
    const at::Tensor features = tensor_of(s, testing::random_motion(rng, s, 15));
    const at::Tensor model = features_to_model_space(features);
    ASSERT_EQ(model.sizes(), (std::vector<int64_t>{1, 15, 6, kModelChannels}));
    EXPECT_TRUE(torch::equal(model.narrow(2, 1, 5).narrow(-1, 0, 9), features.narrow(2, 1, 5))) << "other joints as Θ";
    EXPECT_EQ(model.narrow(2, 1, 5).select(-1, 9).abs().max().item<double>(), 0.0);
    EXPECT_EQ(model[0][0][0][9].item<double>(), 0.0) << "no yaw rate at frame 0";
    for (int64_t t = 0; t < 15; ++t) EXPECT_NEAR(heading_at(model.narrow(-1, 0, 9), t), 0.0, 1e-5) << "no heading";
    const at::Tensor back = model_space_to_features(model, tat::start_heading(features));
    EXPECT_LT(max_difference(back, features), 2e-5) << "clip " << k;
    EXPECT_NEAR(tat::start_heading(features).item<double>(), heading_at(features, 0), 1e-6);
  }
  EXPECT_THROW(features_to_model_space(torch::zeros({1, 0, 4, 9})), std::invalid_argument);
  EXPECT_THROW(features_to_model_space(torch::zeros({1, 3, 4, 10})), std::invalid_argument);
  EXPECT_THROW(model_space_to_features(torch::zeros({1, 3, 4, 9}), torch::zeros({1})), std::invalid_argument);
  EXPECT_THROW(model_space_to_features(torch::zeros({1, 3, 4, 10}), torch::zeros({2})), std::invalid_argument);
}

// The same turning walk on two rigs whose roots face different ways (rig B's
// root is turned 90° about +Y against rig A's, as the MANN dog's against a
// human's): Θ holds different root displacements; model space holds the same
// motion, root orientations included: where the root faces is not in it.
TEST(TatModelSpace, TheSameWalkOnRigsWhoseRootsFaceDifferentWaysIsTheSameMotion) {
  std::mt19937 rng(5);
  const Skeleton s = testing::random_skeleton(rng, 4);
  const Motion base = testing::random_motion(rng, s, 12);
  const Motion walk_a = turning_walk(base, 0.15, 0.0);
  const at::Tensor on_a = tensor_of(s, walk_a);
  const at::Tensor on_b = tensor_of(s, turning_walk(base, 0.15, M_PI / 2.0));
  const auto delta = [](const at::Tensor& f) { return f.select(2, 0).narrow(-1, 0, 3); };
  ASSERT_GT(max_difference(delta(on_a), delta(on_b)), 0.04) << "the rigs should differ in Θ";

  const at::Tensor a = features_to_model_space(on_a), b = features_to_model_space(on_b);
  const auto motion = [](const at::Tensor& m) {
    return torch::cat({m.select(2, 0).narrow(-1, 0, 3), m.select(2, 0).narrow(-1, 9, 1)}, -1);
  };
  EXPECT_LT(max_difference(motion(a), motion(b)), 1e-5);
  // Rig A's root faces its body: its Δx, Δz are Θ's, scaled ...
  const at::Tensor ground = torch::tensor({0, 2});
  EXPECT_LT(max_difference(delta(a).index_select(-1, ground), delta(on_a).index_select(-1, ground) * kRootMotionScale),
            1e-5);
  // ... and every frame holds the root's height, where Θ holds it at frame 0 and steps after.
  for (int t = 0; t < walk_a.frame_count; ++t) {
    EXPECT_NEAR(a[0][t][0][1].item<double>(), walk_a.translation(t, 0).y(), 1e-5) << "frame " << t;
    EXPECT_NEAR(b[0][t][0][1].item<double>(), walk_a.translation(t, 0).y(), 1e-5) << "frame " << t;
  }
  // The yaw rate is the turn per frame, scaled.
  EXPECT_NEAR(a[0][5][0][9].item<double>(), 0.15 * tat::kYawRateScale, 1e-4);
  // The heading is taken out of the root orientation: the lean and roll left are the same on both rigs.
  EXPECT_LT(max_difference(a.select(2, 0).narrow(-1, 3, 6), b.select(2, 0).narrow(-1, 3, 6)), 1e-5);
  // Back with each rig's start heading: each rig's Θ.
  EXPECT_LT(max_difference(model_space_to_features(b, torch::full({1}, M_PI / 2.0)), on_b), 2e-5);
  EXPECT_LT(max_difference(model_space_to_features(a, torch::zeros({1})), on_a), 2e-5);
}

// Another start heading turns the body but not its path.
TEST(TatModelSpace, TheStartHeadingTurnsTheBodyNotItsPath) {
  std::mt19937 rng(7);
  const Skeleton s = testing::random_skeleton(rng, 5);
  const at::Tensor features = tensor_of(s, turning_walk(testing::random_motion(rng, s, 10), 0.1, 0.3));
  const at::Tensor model = features_to_model_space(features);
  const at::Tensor parents = torch::tensor(std::vector<int64_t>(s.parents.begin(), s.parents.end())).view({1, 5});
  at::Tensor offsets = torch::zeros({1, 5, 3});
  for (int j = 0; j < 5; ++j) {
    for (int k = 0; k < 3; ++k) offsets[0][j][k] = s.offsets[j][k];
  }
  const at::Tensor true_positions = tat::features_to_positions(features, parents, offsets).positions;
  const at::Tensor turned = model_space_to_features(model, tat::start_heading(features) + 0.7);
  const at::Tensor turned_positions = tat::features_to_positions(turned, parents, offsets).positions;
  // The root follows the same path ...
  EXPECT_LT(max_difference(turned_positions.select(2, 0), true_positions.select(2, 0)), 1e-5);
  // ... and every joint around it is turned by 0.7 about +Y.
  const at::Tensor turn = torch::tensor({std::cos(0.7), 0.0, std::sin(0.7), 0.0, 1.0, 0.0, -std::sin(0.7), 0.0,
                                         std::cos(0.7)}).view({3, 3}).to(torch::kFloat32);
  const at::Tensor around = true_positions - true_positions.narrow(2, 0, 1);
  const at::Tensor turned_around = turned_positions - turned_positions.narrow(2, 0, 1);
  EXPECT_LT(max_difference(turned_around, torch::matmul(around, turn.t())), 1e-5);
  for (int64_t t = 0; t < 10; ++t) {
    EXPECT_NEAR(std::remainder(heading_at(turned, t) - heading_at(features, t) - 0.7, 2 * M_PI), 0.0, 1e-5);
  }
}

// What the decoder predicts drives the output: a yaw rate turns the root by
// its sum, a body-frame Δ moves it along the body's heading.
TEST(TatModelSpace, PredictedYawRateTurnsTheRootAndMovesItAlongTheBody) {
  at::Tensor model = torch::zeros({1, 8, 2, kModelChannels});
  model.narrow(-1, 3, 1).fill_(1.0);  // identity rot6D everywhere
  model.narrow(-1, 7, 1).fill_(1.0);
  model[0].select(1, 0).select(1, 9).fill_(0.1 * tat::kYawRateScale);  // 0.1 rad a frame (frame 0's is ignored)
  model[0].select(1, 0).select(1, 2).fill_(0.05 * kRootMotionScale);  // forward for the body
  const double offset = M_PI / 2.0;  // the root faces +X at frame 0: the body's +Z is the root's -X
  const at::Tensor features = model_space_to_features(model, torch::full({1}, offset));
  for (int64_t t = 0; t < 8; ++t) {
    EXPECT_NEAR(std::remainder(heading_at(features, t) - offset - 0.1 * t, 2 * M_PI), 0.0, 1e-5) << "frame " << t;
  }
  // World step at frame t = H_t Δ_t: along the body's heading 0.1 t, i.e. +Z turned by 0.1 t.
  const std::vector<int64_t> parents{-1, 0};
  const at::Tensor positions = tat::features_to_positions(features, torch::tensor(parents).view({1, 2}),
                                                          torch::zeros({1, 2, 3}))
                                   .positions;
  for (int64_t t = 1; t < 8; ++t) {
    const at::Tensor step = positions[0][t][0] - positions[0][t - 1][0];
    EXPECT_NEAR(step[0].item<double>(), 0.05 * std::sin(0.1 * t), 1e-5) << "frame " << t;
    EXPECT_NEAR(step[2].item<double>(), 0.05 * std::cos(0.1 * t), 1e-5) << "frame " << t;
  }
}

// Padded frames and joints are zero in Θ: the conversion stays finite there,
// and so do its gradients.
TEST(TatModelSpace, ZeroPaddingGivesFiniteValuesAndGradients) {
  std::mt19937 rng(9);
  const Skeleton s = testing::random_skeleton(rng, 3);
  at::Tensor features = torch::cat({tensor_of(s, testing::random_motion(rng, s, 5)), torch::zeros({1, 3, 3, 9})}, 1);
  features.requires_grad_(true);
  const at::Tensor model = features_to_model_space(features);
  const at::Tensor back = model_space_to_features(model.detach().requires_grad_(true), tat::start_heading(features));
  (model.sum() + back.sum()).backward();
  EXPECT_TRUE(torch::isfinite(model).all().item<bool>());
  EXPECT_TRUE(torch::isfinite(back).all().item<bool>());
  EXPECT_TRUE(torch::isfinite(features.grad()).all().item<bool>());
}

}  // namespace
}  // namespace nec

// Tokenizer reconstruction loss: zero at the target, each term on its own channels, masks.
#include "nec/motion/features.h"
#include "nec/tat/fk.h"
#include "nec/tat/loss.h"
#include "nec/tat/model_space.h"
#include "tat_support.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace nec {
namespace {

using tat::BatchTensors;
using testing::make_batch;
using tat::LossWeights;
using tat::ReconstructionLoss;

struct Fixture {
  std::vector<Skeleton> skeletons;
  BatchTensors batch;
};

// Two clips: 6 joints x 12 frames and 10 joints x 9 frames (padding in both directions).
Fixture two_clips() {
  std::mt19937 rng(11);
  Fixture f;
  std::vector<Motion> motions;
  for (auto [joints, frames] : std::vector<std::pair<int, int>>{{6, 12}, {10, 9}}) {
    f.skeletons.push_back(testing::random_skeleton(rng, joints));
    motions.push_back(testing::random_motion(rng, f.skeletons.back(), frames));
  }
  f.batch = make_batch(f.skeletons, motions);
  return f;
}

ReconstructionLoss loss_of(const at::Tensor& prediction, const BatchTensors& target, double commitment = 0.0) {
  return tat::reconstruction_loss(prediction, target, torch::full({}, commitment), LossWeights{});
}

// A joint with children and a leaf of a skeleton, other than the root.
std::pair<int, int> inner_joint_and_leaf(const Skeleton& s) {
  int inner = -1;
  for (int j = 1; j < s.joint_count() && inner < 0; ++j) {
    if (!s.children(j).empty()) inner = j;
  }
  const std::vector<int> leaves = s.leaves();
  return {inner, leaves.back()};
}

TEST(TatLoss, WeightsValidation) {
  EXPECT_NO_THROW(LossWeights{}.validate());
  LossWeights w;
  w.velocity = -0.1;
  try {
    w.validate();
    ADD_FAILURE() << "accepted a negative weight";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("velocity"), std::string::npos) << e.what();
  }
  w = {};
  w.position = std::nan("");
  EXPECT_THROW(w.validate(), std::invalid_argument);
}

TEST(TatLoss, ZeroAtTheTarget) {
  const Fixture f = two_clips();
  const ReconstructionLoss l = loss_of(f.batch.features.clone(), f.batch);
  EXPECT_EQ(l.total.item<double>(), 0.0);
  EXPECT_EQ(l.rotation, 0.0);
  EXPECT_EQ(l.root, 0.0);
  EXPECT_EQ(l.position, 0.0);
  EXPECT_EQ(l.velocity, 0.0);
  EXPECT_EQ(l.vertical, 0.0);
  EXPECT_EQ(l.commitment, 0.0);
  // The commitment loss is added as it is.
  const ReconstructionLoss with_commitment = loss_of(f.batch.features.clone(), f.batch, 0.125);
  EXPECT_DOUBLE_EQ(with_commitment.total.item<double>(), 0.125);
  EXPECT_DOUBLE_EQ(with_commitment.commitment, 0.125);
}

TEST(TatLoss, EachTermRespondsToItsOwnChannels) {
  const Fixture f = two_clips();
  const auto [inner, leaf] = inner_joint_and_leaf(f.skeletons[0]);
  ASSERT_GT(inner, 0);
  const int frame = 5;

  // An inner joint's rotation at one frame: rotation, positions and velocities, not the root.
  at::Tensor p = f.batch.features.clone();
  p[0][frame][inner].narrow(0, 3, 6).add_(0.3);
  ReconstructionLoss l = loss_of(p, f.batch);
  EXPECT_GT(l.rotation, 0.0);
  EXPECT_EQ(l.root, 0.0);
  EXPECT_GT(l.position, 0.0);
  EXPECT_GT(l.velocity, 0.0);
  EXPECT_EQ(l.vertical, 0.0);

  // A leaf's rotation moves no joint position.
  p = f.batch.features.clone();
  p[0][frame][leaf].narrow(0, 3, 6).add_(0.3);
  l = loss_of(p, f.batch);
  EXPECT_GT(l.rotation, 0.0);
  EXPECT_EQ(l.root, 0.0);
  EXPECT_LT(l.position, 1e-7);
  EXPECT_LT(l.velocity, 1e-7);

  // The root displacement: root, positions (all later frames) and velocity, not rotations.
  p = f.batch.features.clone();
  p[0][frame][0].narrow(0, 0, 3).add_(0.2);
  l = loss_of(p, f.batch);
  EXPECT_EQ(l.rotation, 0.0);
  EXPECT_GT(l.root, 0.0);
  EXPECT_GT(l.position, 0.0);
  EXPECT_GT(l.velocity, 0.0);
  // The root term averages 4 channels (Δ'x, height, Δ'z and the yaw rate) over 12 + 9 real frames. Δy alone
  // lifts the root's height in frames 5 to 11 of clip 0:
  p = f.batch.features.clone();
  p[0][frame][0][1].add_(0.2);
  l = loss_of(p, f.batch);
  EXPECT_NEAR(l.root, 0.2 * 7.0 / 4.0 / 21.0, 1e-6);
  // ... and is one rise per frame, at the path's scale, over the 11 + 8 pairs of real frames.
  EXPECT_NEAR(l.vertical, 0.2 * tat::kRootMotionScale / 19.0, 1e-6);
  // Frame 0's Δy is the start height, not a rise.
  p = f.batch.features.clone();
  p[0][0][0][1].add_(0.2);
  l = loss_of(p, f.batch);
  EXPECT_GT(l.root, 0.0);
  EXPECT_EQ(l.vertical, 0.0);
  // Horizontal Δ counts at the networks' scale, turned into the body's frame (its length kept).
  p = f.batch.features.clone();
  p[0][frame][0][0].add_(0.2);
  const double horizontal = loss_of(p, f.batch).root * 4.0 * 21.0 / tat::kRootMotionScale;  // |Δx'| + |Δz'|
  EXPECT_GE(horizontal, 0.2 - 1e-5);
  EXPECT_LE(horizontal, 0.2 * std::sqrt(2.0) + 1e-5);

  // Turning the root about +Y at one frame (not frame 0): the yaw rate into it and out of it, at the
  // networks' scale; rotations and positions too.
  p = f.batch.features.clone();
  const at::Tensor turn = torch::tensor({std::cos(0.1), 0.0, std::sin(0.1), 0.0, 1.0, 0.0, -std::sin(0.1), 0.0,
                                         std::cos(0.1)}).view({3, 3}).to(torch::kFloat32);
  p[0][frame][0].narrow(0, 3, 6).copy_(
      tat::matrix_to_rot6d(torch::matmul(turn, tat::rot6d_to_matrix(p[0][frame][0].narrow(0, 3, 6)))));
  l = loss_of(p, f.batch);
  EXPECT_NEAR(l.root, 2.0 * 0.1 * tat::kYawRateScale / 4.0 / 21.0, 1e-5);
  EXPECT_GT(l.rotation, 0.0);
  EXPECT_GT(l.position, 0.0);

  // Translation channels of a non-root joint are not part of Θ: nothing.
  p = f.batch.features.clone();
  p[0][frame][inner].narrow(0, 0, 3).add_(0.5);
  l = loss_of(p, f.batch);
  EXPECT_EQ(l.total.item<double>(), 0.0);
}

TEST(TatLoss, PaddingIsExcluded) {
  const Fixture f = two_clips();
  at::Tensor p = f.batch.features.clone();
  p[0].narrow(1, 6, 4).normal_(0.0, 5.0);  // item 0 has 6 of 10 joints
  p[1].narrow(0, 9, 3).normal_(0.0, 5.0);  // item 1 has 9 of 12 frames
  p.requires_grad_(true);
  const ReconstructionLoss l = loss_of(p, f.batch);
  EXPECT_EQ(l.total.item<double>(), 0.0);
  EXPECT_EQ(l.position, 0.0);
  EXPECT_EQ(l.velocity, 0.0);

  // Gradients reach real entries only: with the default weights, and with the positions' and the velocities'
  // terms alone (their FK's backward runs only when they weigh something).
  LossWeights positions_only, velocities_only;
  positions_only.rotation = positions_only.root = positions_only.vertical = 0.0;
  velocities_only = positions_only;
  positions_only.position = 1.0;
  velocities_only.velocity = 1.0;
  for (const auto& [name, weights] : {std::pair<std::string, LossWeights>{"defaults", LossWeights{}},
                                      {"positions", positions_only}, {"velocities", velocities_only}}) {
    at::Tensor q = f.batch.features.clone();
    q.add_(0.1 * torch::randn_like(q));
    q.requires_grad_(true);
    tat::reconstruction_loss(q, f.batch, torch::zeros({}), weights).total.backward();
    const at::Tensor grad = q.grad();
    EXPECT_GT(grad.abs().sum().item<double>(), 0.0) << name;
    EXPECT_EQ(grad[0].narrow(1, 6, 4).abs().sum().item<double>(), 0.0) << name;
    EXPECT_EQ(grad[1].narrow(0, 9, 3).abs().sum().item<double>(), 0.0) << name;
    EXPECT_TRUE(torch::isfinite(grad).all().item<bool>()) << name;
  }
}

// The rotations' term is the mean squared error over the 6 channels of every real joint and frame: an error
// twice as large costs four times as much (under an L1 the tokenizers learnt a still body).
TEST(TatLoss, RotationIsTheMeanSquaredError) {
  const Fixture f = two_clips();
  const auto [inner, leaf] = inner_joint_and_leaf(f.skeletons[0]);
  const double real_entries = f.batch.joint_mask.sum(1).mul(f.batch.frame_mask.sum(1)).sum().item<double>() * 6.0;
  for (const double error : {0.1, 0.2}) {
    at::Tensor p = f.batch.features.clone();
    p[0][3][leaf][4].add_(error);
    p[1][2][inner][7].sub_(error);
    EXPECT_NEAR(loss_of(p, f.batch).rotation, 2.0 * error * error / real_entries, 1e-9) << "error " << error;
  }
}

// Before positions_from_step the positions and velocities do not count; from it on every weight is as set.
TEST(TatLoss, PositionsJoinAtTheirStep) {
  LossWeights w;
  w.position = 0.1;
  w.velocity = 0.05;
  w.positions_from_step = 1500;
  for (const int64_t step : {int64_t{1}, int64_t{1499}}) {
    const LossWeights before = w.at_step(step);
    EXPECT_EQ(before.position, 0.0) << step;
    EXPECT_EQ(before.velocity, 0.0) << step;
    EXPECT_EQ(before.rotation, w.rotation) << step;
    EXPECT_EQ(before.root, w.root) << step;
    EXPECT_EQ(before.vertical, w.vertical) << step;
  }
  for (const int64_t step : {int64_t{1500}, int64_t{2000}}) {
    EXPECT_EQ(w.at_step(step).position, 0.1) << step;
    EXPECT_EQ(w.at_step(step).velocity, 0.05) << step;
  }
  w.positions_from_step = 0;
  EXPECT_EQ(w.at_step(1).position, 0.1);
  w.positions_from_step = -1;
  EXPECT_THROW(w.validate(), std::invalid_argument);
}

TEST(TatLoss, WeightsScaleTheirTerms) {
  const Fixture f = two_clips();
  at::Tensor p = f.batch.features.clone();
  p.add_(0.05 * torch::randn_like(p));
  LossWeights w;
  w.rotation = 2.0;
  w.root = 0.0;
  w.position = 3.0;
  w.velocity = 0.25;
  w.vertical = 1.5;
  const ReconstructionLoss l = tat::reconstruction_loss(p, f.batch, torch::full({}, 0.5), w);
  EXPECT_GT(l.vertical, 0.0);
  EXPECT_NEAR(l.total.item<double>(),
              2.0 * l.rotation + 3.0 * l.position + 0.25 * l.velocity + 1.5 * l.vertical + 0.5, 1e-5);
  EXPECT_THROW(tat::reconstruction_loss(p.narrow(1, 0, 4), f.batch, {}, w), std::invalid_argument);
}

}  // namespace
}  // namespace nec

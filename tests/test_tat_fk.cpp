// Torch forward kinematics of Θ against the double-precision reference in motion/.
#include "nec/motion/features.h"
#include "nec/motion/kinematics.h"
#include "nec/tat/fk.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace nec {
namespace {

using tat::FkResult;

// One item's tensors: features (1, T, J, 9), parents (1, J), offsets (1, J, 3), in `type`.
struct Item {
  at::Tensor features, parents, offsets;
};

Item item_tensors(const Skeleton& skeleton, const Features& f, at::ScalarType type) {
  Item item;
  item.features = torch::from_blob(const_cast<float*>(f.data.data()), {1, f.frame_count, f.joint_count, 9},
                                   torch::kFloat32)
                      .to(type);
  std::vector<int64_t> parents(skeleton.parents.begin(), skeleton.parents.end());
  item.parents = torch::tensor(parents, torch::kLong).view({1, -1});
  std::vector<double> offsets;
  for (const Vec3& o : skeleton.offsets) offsets.insert(offsets.end(), {o.x(), o.y(), o.z()});
  item.offsets = torch::tensor(offsets, torch::kDouble).view({1, -1, 3}).to(type);
  return item;
}

// Largest |torch position - (reference position - start ground position)| over all frames and joints.
double max_difference(const at::Tensor& positions, const std::vector<Vec3>& reference, const Features& f) {
  const at::Tensor p = positions.to(torch::kDouble).contiguous();
  const auto a = p.accessor<double, 4>();
  double worst = 0.0;
  for (int t = 0; t < f.frame_count; ++t) {
    for (int j = 0; j < f.joint_count; ++j) {
      const Vec3 expected = reference[static_cast<size_t>(t) * f.joint_count + j] - Vec3(f.start_xz[0], 0.0, f.start_xz[1]);
      for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(a[0][t][j][k] - expected[k]));
    }
  }
  return worst;
}

at::Tensor matrix_tensor(const Mat3& m) {
  at::Tensor out = torch::empty({3, 3}, torch::kDouble);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out[r][c] = m(r, c);
  return out;
}

double max_matrix_difference(const at::Tensor& a, const Mat3& b) {
  return (a.to(torch::kDouble) - matrix_tensor(b)).abs().max().item<double>();
}

TEST(TatFk, Rot6dMatchesReferenceAndRoundTrips) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> value(-2.0, 2.0);
  double worst_reference = 0.0, worst_round_trip = 0.0;
  for (int i = 0; i < 50; ++i) {
    Rot6 r6;
    for (double& v : r6) v = value(rng);
    const at::Tensor tensor = torch::tensor(std::vector<double>(r6.begin(), r6.end()), torch::kDouble);
    worst_reference = std::max(worst_reference, max_matrix_difference(tat::rot6d_to_matrix(tensor), rot6d_to_matrix(r6)));

    const Mat3 rotation = testing::random_rotation(rng).toRotationMatrix();
    const at::Tensor m = matrix_tensor(rotation);
    const at::Tensor r6_tensor = tat::matrix_to_rot6d(m);
    const Rot6 expected = matrix_to_rot6d(rotation);
    for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(r6_tensor[k].item<double>(), expected[k]);
    worst_round_trip = std::max(worst_round_trip, max_matrix_difference(tat::rot6d_to_matrix(r6_tensor), rotation));
  }
  std::printf("rot6d: max difference to reference %.3g, round trip %.3g\n", worst_reference, worst_round_trip);
  EXPECT_LT(worst_reference, 1e-12);
  EXPECT_LT(worst_round_trip, 1e-12);
  // Batched shapes and zero input (padding) stay finite.
  const at::Tensor zeros = tat::rot6d_to_matrix(torch::zeros({2, 3, 6}));
  EXPECT_EQ(zeros.sizes(), (std::vector<int64_t>{2, 3, 3, 3}));
  EXPECT_TRUE(torch::isfinite(zeros).all().item<bool>());
  EXPECT_THROW(tat::rot6d_to_matrix(torch::zeros({2, 5})), std::invalid_argument);
}

TEST(TatFk, HeadingMatchesReference) {
  std::mt19937 rng(2);
  double worst = 0.0;
  for (int i = 0; i < 200; ++i) {
    const Quat q = testing::random_rotation(rng);
    const at::Tensor h = tat::heading_matrix(matrix_tensor(q.toRotationMatrix()));
    worst = std::max(worst, max_matrix_difference(h, heading_rotation(q).toRotationMatrix()));
  }
  std::printf("heading: max difference to reference %.3g\n", worst);
  EXPECT_LT(worst, 1e-12);

  // Half turn about a tilted axis (w = 0, y != 0): a half turn about +Y, as the reference says.
  const Quat tilted(Eigen::AngleAxisd(M_PI, Vec3(1.0, 1.0, 0.0).normalized()));
  EXPECT_LT(max_matrix_difference(tat::heading_matrix(matrix_tensor(tilted.toRotationMatrix())),
                                  heading_rotation(tilted).toRotationMatrix()),
            1e-12);
  // Half turn about a horizontal axis: no heading, identity, no NaN.
  const Quat flipped(Eigen::AngleAxisd(M_PI, Vec3::UnitX()));
  EXPECT_LT(max_matrix_difference(tat::heading_matrix(matrix_tensor(flipped.toRotationMatrix())), Mat3::Identity()),
            1e-12);
  // A zero matrix (padding) gives the identity too.
  EXPECT_LT(max_matrix_difference(tat::heading_matrix(torch::zeros({3, 3}, torch::kDouble)), Mat3::Identity()), 1e-12);
}

TEST(TatFk, PositionsMatchReferenceForRandomSkeletons) {
  std::mt19937 rng(3);
  for (int joints : {1, 2, 5, 13, 40}) {
    const Skeleton skeleton = testing::random_skeleton(rng, joints);
    const Motion motion = testing::random_motion(rng, skeleton, 24);
    const Features f = encode_features(skeleton, motion);
    const double diameter = std::max(1.0, skeleton.diameter());

    // Float32 against the original motion: only rounding of Θ and of the float math.
    const Item single = item_tensors(skeleton, f, torch::kFloat32);
    const FkResult fk = tat::features_to_positions(single.features, single.parents, single.offsets);
    EXPECT_EQ(fk.positions.sizes(), (std::vector<int64_t>{1, 24, joints, 3}));
    const Pose pose = forward_kinematics(skeleton, motion);
    const double float_error = max_difference(fk.positions, pose.positions, f);

    // Float64 against the reference decode of the same Θ: conventions must agree exactly.
    const Item precise = item_tensors(skeleton, f, torch::kDouble);
    const FkResult fk64 = tat::features_to_positions(precise.features, precise.parents, precise.offsets);
    const Motion decoded = decode_features(skeleton, f);
    const Pose decoded_pose = forward_kinematics(skeleton, decoded);
    const double double_error = max_difference(fk64.positions, decoded_pose.positions, f);
    double rotation_error = 0.0;
    for (int t = 0; t < f.frame_count; ++t) {
      for (int j = 0; j < joints; ++j) {
        rotation_error = std::max(rotation_error, max_matrix_difference(fk64.global_rotations[0][t][j],
                                                                        decoded_pose.rotation(t, j).toRotationMatrix()));
      }
    }
    std::printf("J=%2d: float32 vs motion %.3g (diameter %.3g), float64 vs decode %.3g, rotations %.3g\n", joints,
                float_error, diameter, double_error, rotation_error);
    EXPECT_LT(float_error, 1e-4 * diameter);
    EXPECT_LT(double_error, 1e-9 * diameter);
    EXPECT_LT(rotation_error, 1e-9);
  }
}

TEST(TatFk, PaddedBatchGivesTheSamePositionsAsSingles) {
  std::mt19937 rng(4);
  const std::vector<int> joint_counts{4, 9};
  std::vector<Skeleton> skeletons;
  std::vector<Features> features;
  for (int joints : joint_counts) {
    skeletons.push_back(testing::random_skeleton(rng, joints));
    features.push_back(encode_features(skeletons.back(), testing::random_motion(rng, skeletons.back(), 10)));
  }
  const int64_t max_joints = 9;
  at::Tensor batch_features = torch::zeros({2, 10, max_joints, 9});
  at::Tensor batch_parents = torch::full({2, max_joints}, -1, torch::kLong);
  at::Tensor batch_offsets = torch::zeros({2, max_joints, 3});
  std::vector<FkResult> singles;
  for (int i = 0; i < 2; ++i) {
    const Item item = item_tensors(skeletons[i], features[i], torch::kFloat32);
    const int64_t joints = joint_counts[i];
    batch_features[i].narrow(1, 0, joints).copy_(item.features[0]);
    batch_parents[i].narrow(0, 0, joints).copy_(item.parents[0]);
    batch_offsets[i].narrow(0, 0, joints).copy_(item.offsets[0]);
    singles.push_back(tat::features_to_positions(item.features, item.parents, item.offsets));
  }
  const FkResult batched = tat::features_to_positions(batch_features, batch_parents, batch_offsets);
  for (int i = 0; i < 2; ++i) {
    const int64_t joints = joint_counts[i];
    const double difference =
        (batched.positions[i].narrow(1, 0, joints) - singles[i].positions[0]).abs().max().item<double>();
    std::printf("item %d (J=%lld): max difference batched vs alone %.3g\n", i, static_cast<long long>(joints),
                difference);
    EXPECT_LT(difference, 1e-5);
  }
  // Padded joints sit at the root and are finite.
  const at::Tensor padded = batched.positions[0].narrow(1, 4, 5);
  EXPECT_LT((padded - batched.positions[0].narrow(1, 0, 1)).abs().max().item<double>(), 1e-6);
  EXPECT_TRUE(torch::isfinite(batched.global_rotations).all().item<bool>());
}

TEST(TatFk, GradientsMatchFiniteDifferences) {
  std::mt19937 rng(5);
  const Skeleton skeleton = testing::random_skeleton(rng, 5);
  const Features f = encode_features(skeleton, testing::random_motion(rng, skeleton, 3));
  Item item = item_tensors(skeleton, f, torch::kDouble);
  item.features.requires_grad_(true);
  item.offsets.requires_grad_(true);
  const at::Tensor weights = torch::randn({1, 3, 5, 3}, torch::kDouble);
  auto objective = [&](const at::Tensor& features, const at::Tensor& offsets) {
    return (tat::features_to_positions(features, item.parents, offsets).positions * weights).sum();
  };
  objective(item.features, item.offsets).backward();
  const at::Tensor feature_grad = item.features.grad(), offset_grad = item.offsets.grad();
  ASSERT_TRUE(feature_grad.defined());
  ASSERT_TRUE(offset_grad.defined());

  torch::NoGradGuard no_grad;
  const double step = 1e-6;
  double worst = 0.0;
  auto check = [&](const at::Tensor& parameter, const at::Tensor& gradient) {
    const at::Tensor flat = parameter.view({-1});
    for (int64_t i = 0; i < flat.numel(); ++i) {
      const double saved = flat[i].item<double>();
      flat[i] = saved + step;
      const double up = objective(item.features, item.offsets).item<double>();
      flat[i] = saved - step;
      const double down = objective(item.features, item.offsets).item<double>();
      flat[i] = saved;
      worst = std::max(worst, std::abs((up - down) / (2 * step) - gradient.view({-1})[i].item<double>()));
    }
  };
  check(item.features, feature_grad);
  check(item.offsets, offset_grad);
  std::printf("max |autograd - finite difference| %.3g, |grad| max %.3g\n", worst,
              feature_grad.abs().max().item<double>());
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(offset_grad.abs().sum().item<double>(), 0.0);
}

// Windows cut from a clip that turns, each turned to the clip's start heading
// as the tokenizer encodes them (the same as motion's turn_to_heading on
// training crops), then continued from one another as decoding does: the
// clip's own orientations come back.
TEST(TatFk, WindowsAlignedToTheStartHeadingAndContinuedGiveTheClipBack) {
  std::mt19937 rng(71);
  const Skeleton s = testing::random_skeleton(rng, 5);
  Features clip = encode_features(s, testing::random_motion(rng, s, 20));
  turn_to_heading(clip, 2.0);  // a clip whose root does not face +Z at its start
  const at::Tensor all = torch::from_blob(clip.data.data(), {20, 5, 9}, torch::kFloat32).clone();
  const std::vector<int64_t> starts{0, 6, 12};
  std::vector<at::Tensor> cut;
  for (int64_t start : starts) cut.push_back(all.narrow(0, start, 8));
  const at::Tensor windows = torch::stack(cut);  // (3, 8, 5, 9)

  const at::Tensor aligned = tat::align_window_headings(windows);
  EXPECT_TRUE(torch::allclose(aligned[0], windows[0], 1e-6, 1e-6));
  for (size_t k = 0; k < starts.size(); ++k) {
    Features crop;  // as training crops are turned
    crop.frame_count = 8;
    crop.joint_count = 5;
    crop.data.assign(cut[k].data_ptr<float>(), cut[k].data_ptr<float>() + cut[k].numel());
    const double turned = turn_to_heading(crop, root_heading(clip, 0));
    if (k > 0) {
      EXPECT_GT(std::abs(turned), 1e-3) << "window " << k << " should need turning";
    }
    const at::Tensor expected = torch::from_blob(crop.data.data(), {8, 5, 9}, torch::kFloat32);
    EXPECT_TRUE(torch::allclose(aligned[k], expected, 1e-5, 1e-5)) << "window " << k;
  }
  const at::Tensor continued = tat::continue_window_headings(aligned, starts);
  EXPECT_TRUE(torch::allclose(continued, windows, 1e-4, 1e-4))
      << "max difference " << (continued - windows).abs().max().item<double>();
  EXPECT_THROW(tat::continue_window_headings(aligned, {0, 6}), std::invalid_argument);
  EXPECT_THROW(tat::continue_window_headings(aligned, {0, 6, 6}), std::invalid_argument);  // not in order
  EXPECT_THROW(tat::continue_window_headings(aligned, {0, 6, 15}), std::invalid_argument);  // a gap
  EXPECT_THROW(tat::align_window_headings(torch::zeros({0, 8, 5, 9})), std::invalid_argument);

  // Back to back (no overlap): each window starts with the heading the one before ends with.
  const at::Tensor back_to_back = tat::continue_window_headings(aligned, {0, 8, 16});
  for (int64_t k = 1; k < 3; ++k) {
    const at::Tensor before = tat::heading_matrix(tat::rot6d_to_matrix(back_to_back[k - 1][7][0].narrow(0, 3, 6)));
    const at::Tensor after = tat::heading_matrix(tat::rot6d_to_matrix(back_to_back[k][0][0].narrow(0, 3, 6)));
    EXPECT_TRUE(torch::allclose(before, after, 1e-5, 1e-5)) << "window " << k;
  }
}

TEST(TatFk, RejectsBadShapes) {
  EXPECT_THROW(tat::features_to_positions(torch::zeros({1, 2, 3, 8}), torch::zeros({1, 3}, torch::kLong),
                                          torch::zeros({1, 3, 3})),
               std::invalid_argument);
  EXPECT_THROW(tat::features_to_positions(torch::zeros({1, 2, 3, 9}), torch::zeros({1, 4}, torch::kLong),
                                          torch::zeros({1, 3, 3})),
               std::invalid_argument);
}

}  // namespace
}  // namespace nec

// diffusion/: the noise schedule and DDIM steps on known numbers; TreePE and
// RestPE; windows of long motions (a window's own frame is the crop's, on a
// turning walk); the denoiser's masks, adaLN-Zero start and independent
// frames of the pose model; sampling repeats by seed, sample by sample; and
// a tiny denoiser learns which motion each caption means, and its samples
// swing as far as the real motions (none before it learns).
#include "nec/diffusion/denoiser.h"
#include "nec/diffusion/noise_schedule.h"
#include "nec/diffusion/sampling.h"
#include "nec/diffusion/skeleton_inputs.h"
#include "nec/diffusion/training.h"
#include "nec/diffusion/windows.h"
#include "nec/motion/features.h"
#include "nec/motion/files.h"
#include "nec/tat/batch_tensors.h"
#include "nec/tat/model_space.h"
#include "nec/train/config_fields.h"
#include "test_support.h"
#include "text_encoder_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

namespace nec {
namespace {

using diffusion::DenoiserConfig;
using diffusion::MotionDenoiser;
using diffusion::NoiseSchedule;
using diffusion::SkeletonInputs;

constexpr int64_t kC = tat::kModelChannels;

double max_difference(const at::Tensor& a, const at::Tensor& b) { return (a - b).abs().max().item<double>(); }

DenoiserConfig tiny_config() {
  DenoiserConfig c;
  c.dim = 32;
  c.heads = 2;
  c.layers = 2;
  c.feedforward = 64;
  c.max_frames = 16;
  c.skeleton_dim = 8;
  c.noise_steps = 100;
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

// Skeleton inputs of B copies of a 5-joint tree (root with two chains) with `real` joints, OwO-like random embeddings.
SkeletonInputs five_joints(int64_t b, int64_t real = 5) {
  const at::Tensor parents = torch::tensor({-1, 0, 1, 0, 3}, torch::kInt64).view({1, 5}).expand({b, 5}).clone();
  at::Tensor mask = torch::ones({b, 5}, torch::kBool);
  if (real < 5) {
    mask.narrow(1, real, 5 - real).fill_(false);
    parents.narrow(1, real, 5 - real).fill_(-1);
  }
  const at::Tensor offsets = torch::randn({b, 5, 3}) * 0.2 * mask.unsqueeze(-1);
  return diffusion::make_skeleton_inputs(parents, offsets, mask, torch::randn({b, 5, 8}) * mask.unsqueeze(-1));
}

// Every parameter of `model` whose name starts with one of `prefixes` set to random values.
void randomize(diffusion::MotionDenoiserImpl& model, const std::vector<std::string>& prefixes) {
  torch::NoGradGuard no_grad;
  for (auto& item : model.named_parameters()) {
    for (const std::string& prefix : prefixes) {
      if (item.key().rfind(prefix, 0) == 0) item.value().copy_(torch::randn_like(item.value()) * 0.2);
    }
  }
}

TEST(DiffusionSchedule, CosineScheduleAndDdimStepsOnKnownNumbers) {
  const NoiseSchedule schedule(1000);
  EXPECT_GT(schedule.alpha_bar(0), 0.999);
  EXPECT_LT(schedule.alpha_bar(999), 1e-4);
  for (int64_t t = 1; t < 1000; ++t) ASSERT_LT(schedule.alpha_bar(t), schedule.alpha_bar(t - 1));
  // Halfway the cosine schedule keeps about half of the signal's variance.
  EXPECT_NEAR(schedule.alpha_bar(499), 0.5, 0.02);

  const at::Tensor x0 = torch::randn({2, 3, 4, kC}), noise = torch::randn({2, 3, 4, kC});
  const at::Tensor t = torch::tensor({10, 700}, torch::kInt64);
  const at::Tensor x_t = schedule.add_noise(x0, noise, t);
  const double a = schedule.alpha_bar(700);
  EXPECT_LT(max_difference(x_t[1], std::sqrt(a) * x0[1] + std::sqrt(1 - a) * noise[1]), 1e-5);

  // With the true x0, a DDIM step lands on the same noise at the earlier timestep.
  const at::Tensor earlier = schedule.ddim_step(x_t[1], x0[1], 700, 300);
  const double b = schedule.alpha_bar(300);
  EXPECT_LT(max_difference(earlier, std::sqrt(b) * x0[1] + std::sqrt(1 - b) * noise[1]), 1e-4);
  EXPECT_TRUE(schedule.ddim_step(x_t[1], x0[1], 700, -1).equal(x0[1]));

  using diffusion::TimestepSpacing;
  const std::vector<int64_t> uniform = schedule.sampling_timesteps(50, TimestepSpacing::kUniform);
  EXPECT_EQ(uniform.front(), 999);
  EXPECT_EQ(uniform[1], 979);
  EXPECT_EQ(uniform.back(), 0);
  EXPECT_EQ(schedule.sampling_timesteps(10, TimestepSpacing::kQuadratic),
            (std::vector<int64_t>{999, 789, 604, 444, 308, 197, 111, 49, 12, 0}));
  EXPECT_EQ(schedule.sampling_timesteps(1, TimestepSpacing::kQuadratic), std::vector<int64_t>{999});
  // Any count: from 999 down to 0, never a timestep twice (rounding would repeat the quadratic's low ones).
  for (const TimestepSpacing spacing : {TimestepSpacing::kUniform, TimestepSpacing::kQuadratic}) {
    for (int64_t count = 2; count <= 1000; ++count) {
      const std::vector<int64_t> ts = schedule.sampling_timesteps(count, spacing);
      ASSERT_EQ(static_cast<int64_t>(ts.size()), count);
      ASSERT_EQ(ts.front(), 999) << count;
      ASSERT_EQ(ts.back(), 0) << count;
      for (size_t i = 1; i < ts.size(); ++i) ASSERT_LT(ts[i], ts[i - 1]) << to_string(spacing) << " " << count;
    }
  }
  EXPECT_THROW(schedule.sampling_timesteps(1001, TimestepSpacing::kUniform), std::invalid_argument);
  EXPECT_THROW(schedule.sampling_timesteps(0, TimestepSpacing::kUniform), std::invalid_argument);
  EXPECT_THROW(NoiseSchedule(1), std::invalid_argument);
}


// On Gaussian data N(μ, s²) the best x0 estimate is known in closed form, and so is where the sampler's ODE
// takes a starting point: x_t = √ᾱ μ + √(ᾱ s² + 1 − ᾱ) z keeps z. The second-order solver gets closer in 20
// steps than DDIM in 50 (0.018 against 0.027; DDIM in 20: 0.067).
TEST(DiffusionSchedule, DpmSolverFollowsTheSamplingPathCloserThanDdimInFewSteps) {
  const NoiseSchedule schedule(1000);
  const double mu = 1.5, s = 0.3;
  const auto best_x0 = [&](const at::Tensor& x, int64_t t) {
    const double a = schedule.alpha_bar(t);
    return mu + std::sqrt(a) * s * s / (a * s * s + 1 - a) * (x - std::sqrt(a) * mu);
  };
  const at::Tensor start = torch::linspace(-2.0, 2.0, 9, torch::kFloat64);
  const double a_start = schedule.alpha_bar(999);
  const at::Tensor z = (start - std::sqrt(a_start) * mu) / std::sqrt(a_start * s * s + 1 - a_start);
  const at::Tensor exact = best_x0(std::sqrt(schedule.alpha_bar(0)) * mu + std::sqrt(schedule.alpha_bar(0) * s * s + 1 - schedule.alpha_bar(0)) * z, 0);
  const auto sample = [&](int64_t steps, bool second_order) {
    at::Tensor x = start.clone(), x0, earlier_x0;
    int64_t earlier = -1;
    const std::vector<int64_t> ts = schedule.sampling_timesteps(steps, diffusion::TimestepSpacing::kUniform);
    for (int64_t i = 0; i < steps; ++i) {
      const int64_t t = ts[static_cast<size_t>(i)], previous = i + 1 < steps ? ts[static_cast<size_t>(i + 1)] : -1;
      x0 = best_x0(x, t);
      x = second_order ? schedule.dpm_solver_step(x, x0, earlier_x0, earlier, t, previous)
                       : schedule.ddim_step(x, x0, t, previous);
      earlier_x0 = x0;
      earlier = t;
    }
    return max_difference(x, exact);
  };
  const double ddim_20 = sample(20, false), ddim_50 = sample(50, false), dpm_20 = sample(20, true);
  EXPECT_LT(sample(1000, false), 0.002);  // many small steps follow the path
  EXPECT_LT(dpm_20, 0.5 * ddim_20) << "DDIM " << ddim_20 << ", DPM-Solver++ " << dpm_20;
  EXPECT_LT(dpm_20, ddim_50) << "DDIM " << ddim_50 << ", DPM-Solver++ " << dpm_20;

  // The first step, and a step whose two estimates agree, are DDIM steps.
  const at::Tensor x = torch::randn({3, 4}), a = torch::randn({3, 4}), b = torch::randn({3, 4});
  EXPECT_TRUE(schedule.dpm_solver_step(x, a, {}, -1, 700, 300).equal(schedule.ddim_step(x, a, 700, 300)));
  EXPECT_TRUE(schedule.dpm_solver_step(x, a, b, 900, 700, 0).equal(schedule.ddim_step(x, a, 700, 0)));
  EXPECT_LT(max_difference(schedule.dpm_solver_step(x, a, a, 900, 700, 300), schedule.ddim_step(x, a, 700, 300)), 1e-5);
  EXPECT_GT(max_difference(schedule.dpm_solver_step(x, a, b, 900, 700, 300), schedule.ddim_step(x, a, 700, 300)), 1e-2);
}
TEST(DiffusionSkeleton, TreePositionsFollowThePathFromTheRoot) {
  // 0 root; 1, 3 its children; 2 under 1; 4 under 3; 5 padding.
  const at::Tensor parents = torch::tensor({-1, 0, 1, 0, 3, -1}, torch::kInt64).view({1, 6});
  const at::Tensor tree = diffusion::tree_positions(parents)[0];
  ASSERT_EQ(tree.size(1), diffusion::kTreeFeatures);
  const auto one = [&](int64_t joint, int64_t level, int64_t branch) {
    return tree[joint][level * diffusion::kTreeBranches + branch].item<float>();
  };
  EXPECT_EQ(tree[0].sum().item<float>(), 0.0f);       // the root
  EXPECT_EQ(tree[5].sum().item<float>(), 0.0f);       // padding reads as a root
  EXPECT_EQ(one(1, 0, 0), 1.0f);                      // first child
  EXPECT_EQ(one(3, 0, 1), 1.0f);                      // second child
  EXPECT_EQ(one(2, 0, 0) + one(2, 1, 0), 2.0f);       // first child's first child
  EXPECT_EQ(one(4, 0, 1) + one(4, 1, 0), 2.0f);       // second child's first child
  EXPECT_EQ(tree[4].sum().item<float>(), 2.0f);       // one one-hot per level
  EXPECT_GT(max_difference(tree[2], tree[4]), 0.5);   // same depth, other branch

  const at::Tensor rest = diffusion::rest_positions(torch::tensor({0.25f, -0.5f, 0.0f}).view({1, 1, 3}));
  ASSERT_EQ(rest.size(2), diffusion::kRestFeatures);
  EXPECT_FLOAT_EQ(rest[0][0][0].item<float>(), 0.25f);
  EXPECT_NEAR(rest[0][0][3].item<float>(), std::sin(0.25 * M_PI), 1e-6);   // sin(2^0 π x)
  EXPECT_NEAR(rest[0][0][13].item<float>(), std::cos(-1.0 * M_PI), 1e-6);  // cos(2^1 π y)
}

TEST(DiffusionWindows, WindowsCoverTheMotionAndEverySegmentHasOne) {
  const auto one = diffusion::layout_windows({90}, 120, 0);
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0].frames, 90);

  const auto many = diffusion::layout_windows({300}, 120, 0);
  ASSERT_GE(many.size(), 3u);
  EXPECT_EQ(many.front().start, 0);
  EXPECT_EQ(many.back().start + many.back().frames, 300);
  for (size_t k = 1; k < many.size(); ++k) {
    EXPECT_EQ(many[k].frames, 120);
    EXPECT_GE(many[k - 1].start + many[k - 1].frames - many[k].start, 30);  // they share at least the overlap
  }

  const auto segments = diffusion::layout_windows({60, 60, 200}, 120, 0);
  std::vector<bool> seen(3, false);
  for (const auto& w : segments) seen[static_cast<size_t>(w.segment)] = true;
  EXPECT_EQ(seen, std::vector<bool>({true, true, true}));
  EXPECT_THROW(diffusion::layout_windows({0}, 120, 0), std::invalid_argument);

  const at::Tensor w = diffusion::window_weights(8, 4, false, true);
  EXPECT_LT(w[0].item<float>(), 0.2f);
  EXPECT_FLOAT_EQ(w[7].item<float>(), 1.0f);
}

TEST(DiffusionWindows, AWindowSeesTheMotionAsACropOfItsOwn) {
  // A turning walk: the model space of frames [s, s + n) on their own is the
  // whole motion's, the horizontal displacement turned by the heading at s.
  std::mt19937 rng(5);
  const Skeleton skeleton = testing::random_skeleton(rng, 5);
  Motion motion = testing::random_motion(rng, skeleton, 40);
  Vec3 position(0.1, 1.0, 0.0);
  for (int t = 0; t < motion.frame_count; ++t) {
    const double heading = 0.04 * t;
    position += Eigen::AngleAxisd(heading, Vec3::UnitY()) * Vec3(0.01, 0.0, 0.05);
    motion.rotation(t, 0) = Quat(Eigen::AngleAxisd(heading, Vec3::UnitY()) * Eigen::AngleAxisd(0.1 * std::sin(t), Vec3::UnitX()));
    motion.translation(t, 0) = position;
  }
  const auto model_space = [&](const Motion& m) {
    Features f = encode_features(skeleton, m);
    return tat::features_to_model_space(
        torch::from_blob(f.data.data(), {1, f.frame_count, f.joint_count, kFeatureSize}, torch::kFloat32).clone());
  };
  const at::Tensor whole = model_space(motion);
  const int64_t s = 12, n = 20;
  const at::Tensor crop = model_space(motion.slice(static_cast<int>(s), static_cast<int>(s + n)));
  const at::Tensor yaw = whole.select(2, 0).select(2, 9).cumsum(1).select(1, s) / tat::kYawRateScale;  // (1)
  EXPECT_NEAR(yaw.item<double>(), 0.04 * s, 1e-4);
  const at::Tensor local = diffusion::turn_horizontal(whole.narrow(1, s, n), yaw);
  // Frame 0 of a crop does not move; from frame 1 on every channel agrees.
  EXPECT_LT(max_difference(local.narrow(1, 1, n - 1), crop.narrow(1, 1, n - 1)), 1e-4);
  EXPECT_LT(max_difference(diffusion::turn_horizontal(local, -yaw), whole.narrow(1, s, n)), 1e-5);
}

TEST(DiffusionDenoiser, PaddingIsNeverReadAndTemporalBlocksStartAsTheIdentity) {
  torch::manual_seed(1);
  MotionDenoiser model(tiny_config());
  model->eval();
  randomize(*model, {"spatial.", "final_modulation.", "out.", "motion_in.", "owo_in.", "time_in.", "caption_in."});
  torch::NoGradGuard no_grad;
  const SkeletonInputs skeletons = five_joints(2, 4);
  const at::Tensor caption = model->caption_condition(piece_batch({{2, 3}, {4}}), {});
  const at::Tensor t = torch::tensor({5, 60}, torch::kInt64);
  at::Tensor frame_mask = torch::ones({2, 6}, torch::kBool);
  frame_mask[1].narrow(0, 4, 2).fill_(false);
  const at::Tensor x = torch::randn({2, 6, 5, kC});

  // adaLN-Zero: temporal blocks add nothing until they are trained.
  const at::Tensor pose = model->forward(x, t, caption, skeletons, frame_mask, false);
  const at::Tensor motion = model->forward(x, t, caption, skeletons, frame_mask, true);
  EXPECT_LT(max_difference(pose, motion), 1e-6);
  randomize(*model, {"temporal.", "frame_in."});
  const at::Tensor temporal = model->forward(x, t, caption, skeletons, frame_mask, true);
  EXPECT_GT(max_difference(pose, temporal), 1e-3);

  // Padded joints and frames: whatever they hold, the real ones' outputs stay.
  at::Tensor changed = x.clone();
  changed.select(2, 4).normal_();
  changed[1].narrow(0, 4, 2).normal_();
  const at::Tensor again = model->forward(changed, t, caption, skeletons, frame_mask, true);
  EXPECT_LT(max_difference(again.narrow(2, 0, 4)[0], temporal.narrow(2, 0, 4)[0]), 1e-5);
  EXPECT_LT(max_difference(again[1].narrow(0, 0, 4).narrow(1, 0, 4), temporal[1].narrow(0, 0, 4).narrow(1, 0, 4)), 1e-5);

  // The pose model reads frames on their own; the motion model does not.
  at::Tensor one_frame = x.clone();
  one_frame[0][3].normal_();
  EXPECT_LT(max_difference(model->forward(one_frame, t, caption, skeletons, frame_mask, false)[0][0], pose[0][0]), 1e-6);
  EXPECT_GT(max_difference(model->forward(one_frame, t, caption, skeletons, frame_mask, true)[0][0], temporal[0][0]), 1e-4);

  // Stage two trains only what stage one does not have.
  size_t pose_count = model->pose_parameters().size(), temporal_count = model->temporal_parameters().size();
  EXPECT_EQ(pose_count + temporal_count, model->parameters().size());
  EXPECT_THROW(model->forward(torch::randn({1, 17, 5, kC}), t.narrow(0, 0, 1), caption.narrow(0, 0, 1),
                              five_joints(1), {}, true),
               std::invalid_argument);
}

TEST(DiffusionDenoiser, StatisticsStandardizeAndKeepTheHorizontalPlaneRound) {
  MotionDenoiser model(tiny_config());
  at::Tensor a = torch::randn({30, 3, kC}) * 2 + 1, b = torch::randn({20, 5, kC}) * 0.5 - 3;
  for (at::Tensor* clip : {&a, &b}) {  // the other joints' root channels are 0 in model space
    clip->narrow(1, 1, clip->size(1) - 1).narrow(2, 0, 3).zero_();
    clip->narrow(1, 1, clip->size(1) - 1).narrow(2, 9, 1).zero_();
  }
  a.select(1, 0).select(1, 2).fill_(3.0);  // the root walks forward along z
  model->fit_statistics({a, b});
  const at::Tensor s = model->standardize(a);
  // The root's horizontal displacement keeps mean 0 and one scale for x and z.
  EXPECT_NEAR(s[0][0][2].item<double>() / 3.0, s[1][0][2].item<double>() / 3.0, 1e-6);
  EXPECT_LT(max_difference(model->unstandardize(s), a), 1e-4);
  const at::Tensor others = model->standardize(torch::cat({a.narrow(1, 1, 2).reshape({-1, kC}), b.narrow(1, 1, 4).reshape({-1, kC})}).unsqueeze(1).expand({-1, 2, kC}))
                                .select(1, 1).narrow(1, 3, 6);
  EXPECT_LT(others.mean(0).abs().max().item<double>(), 1e-4);
  EXPECT_NEAR(others.std(0, false).mean().item<double>(), 1.0, 1e-3);
}

TEST(DiffusionSampling, SamplesRepeatBySeedSampleBySample) {
  torch::manual_seed(2);
  MotionDenoiser model(tiny_config());
  randomize(*model, {"spatial.", "temporal.", "frame_in.", "final_modulation.", "out.", "motion_in.", "owo_in."});
  model->eval();
  const NoiseSchedule schedule(100);
  const SkeletonInputs skeleton = five_joints(1);
  at::Tensor captions;
  {
    torch::NoGradGuard no_grad;
    captions = model->caption_condition(piece_batch({{2, 3}, {4, 5}}), {});
  }
  diffusion::DiffusionSamplingOptions options;
  options.steps = 5;
  options.seed = 9;
  const auto two = diffusion::sample_motions(*model, schedule, skeleton, captions.narrow(0, 0, 1), {12}, 2, options);
  options.seed = 10;
  const auto one = diffusion::sample_motions(*model, schedule, skeleton, captions.narrow(0, 0, 1), {12}, 1, options);
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[0].sizes(), (std::vector<int64_t>{12, 5, kC}));
  // Rounding only: a batch of two goes through other BLAS blockings than one sample, and five denoising steps
  // amplify the difference (1.0e-5 seen); a mixed-up seed or sample differs by the motion's own scale.
  EXPECT_LT(max_difference(two[1], one[0]), 5e-5);
  EXPECT_GT(max_difference(two[0], two[1]), 1e-3);
  // Channels a joint does not use stay 0.
  EXPECT_EQ(two[0].narrow(1, 1, 4).narrow(2, 0, 3).abs().max().item<float>(), 0.0f);

  // Two segments longer than a window: overlapping windows, one motion of their summed length.
  const auto long_motion = diffusion::sample_motions(*model, schedule, skeleton, captions, {14, 20}, 1, options);
  EXPECT_EQ(long_motion[0].size(0), 34);
  EXPECT_TRUE(torch::isfinite(long_motion[0]).all().item<bool>());
  options.steps = 101;
  EXPECT_THROW(diffusion::sample_motions(*model, schedule, skeleton, captions.narrow(0, 0, 1), {12}, 1, options),
               std::invalid_argument);
}

TEST(DiffusionLoss, VelocityLossSeesJitterNotAnOffsetAndSkipsUnusedFrames) {
  const at::Tensor target = torch::randn({2, 6, 3, kC});
  at::Tensor used = torch::ones({2, 6, 3, kC}, torch::kBool);
  // A prediction off by the same amount in every frame has the target's velocities.
  EXPECT_NEAR(diffusion::velocity_loss(target + 0.7, target, used, 2).item<double>(), 0.0, 1e-10);
  EXPECT_NEAR(diffusion::denoising_loss(target + 0.7, target, used, 2).item<double>(), 0.49, 1e-5);
  // Item 0 off by +e, -e, +e, ... in every channel: each of its 5 frame differences is off by 2e.
  const double e = 0.1;
  const at::Tensor signs = torch::tensor({1.0f, -1.0f, 1.0f, -1.0f, 1.0f, -1.0f}).view({1, 6, 1, 1});
  at::Tensor predicted = target.clone();
  predicted[0] += e * signs[0];
  EXPECT_NEAR(diffusion::velocity_loss(predicted, target, used, 2).item<double>(), 4 * e * e / 2, 1e-6);
  // The last two frames of item 0 unused: its differences are those among frames 0-3, still 2e each; the
  // frame after an unused one never counts.
  used[0].narrow(0, 4, 2).fill_(false);
  predicted[0][5] += 100.0;
  EXPECT_NEAR(diffusion::velocity_loss(predicted, target, used, 2).item<double>(), 4 * e * e / 2, 1e-6);
  // Item 1 jitters too: both items count, per item, over all items.
  predicted[1] += 2 * e * signs[0];
  EXPECT_NEAR(diffusion::velocity_loss(predicted, target, used, 2).item<double>(), (4 * e * e + 16 * e * e) / 2, 1e-6);
}

TEST(DiffusionLearning, ATinyDenoiserLearnsWhichMotionEachCaptionMeans) {
  // Caption A: joint 1 swings with sin(t); caption B: with −sin(t). Learnt in
  // standardized space from the data's statistics, sampled with guidance.
  torch::manual_seed(4);
  DenoiserConfig config = tiny_config();
  config.max_frames = 8;
  MotionDenoiser model(config);
  const NoiseSchedule schedule(config.noise_steps);
  const SkeletonInputs one = five_joints(1);
  const SkeletonInputs skeletons = one.select(torch::zeros({8}, torch::kInt64));
  const auto motion_of = [](double sign) {
    at::Tensor m = torch::zeros({8, 5, kC});
    for (int64_t j = 0; j < 5; ++j) {
      m.select(1, j).select(1, 3).fill_(1.0);  // identity rot6D
      m.select(1, j).select(1, 7).fill_(1.0);
    }
    m.select(1, 0).select(1, 1).fill_(0.9);  // root height
    for (int64_t t = 0; t < 8; ++t) m[t][1][4] = static_cast<float>(sign * std::sin(0.8 * static_cast<double>(t)));
    return m;
  };
  const at::Tensor a = motion_of(1.0), b = motion_of(-1.0);
  model->fit_statistics({a, b});
  // The two motions as a batch of real clips (Θ), to measure how much of their swing whole samples keep.
  tat::BatchTensors truth;
  truth.features = tat::model_space_to_features(torch::stack({a, b}), torch::zeros({2}));
  truth.joint_mask = torch::ones({2, 5}, torch::kBool);
  truth.frame_mask = torch::ones({2, 8}, torch::kBool);
  truth.parents = torch::tensor({-1, 0, 1, 0, 3}, torch::kInt64).view({1, 5}).expand({2, 5}).clone();
  truth.offsets = torch::randn({2, 5, 3}) * 0.2;
  diffusion::DiffusionSamplingOptions options;
  options.steps = 20;
  options.guidance = 2.0;
  const auto sample_and_measure = [&] {
    model->eval();
    at::Tensor conditions;
    {
      torch::NoGradGuard no_grad;
      conditions = model->caption_condition(piece_batch({{2}, {3}}), {});
    }
    return diffusion::sampled_turning(*model, schedule, truth, skeletons.select(torch::zeros({2}, torch::kInt64)),
                                      conditions, options);
  };
  // Untrained, the output layer is zero: every sample is the data's mean, joint 1 at rest and still.
  const diffusion::SampledTurning untrained = sample_and_measure();
  EXPECT_LT(untrained.pose_kept(), 0.05);
  EXPECT_LT(untrained.speed_kept(), 0.05);
  const at::Tensor x0 = model->standardize(torch::stack({a, b, a, b, a, b, a, b}));
  const at::Tensor used = diffusion::channel_mask(skeletons.joint_mask).unsqueeze(1).expand({8, 8, 5, kC});
  const text::TextBatch captions = piece_batch({{2}, {3}, {2}, {3}, {2}, {3}, {2}, {3}});
  torch::optim::AdamW optimizer(model->parameters(), torch::optim::AdamWOptions(3e-3).weight_decay(0.0));
  model->train();
  double first = 0, last = 0;
  for (int step = 0; step < 300; ++step) {
    const at::Tensor t = torch::randint(0, config.noise_steps, {8}, torch::kInt64);
    const at::Tensor drop = torch::rand({8}) < 0.1;
    const at::Tensor x_t = schedule.add_noise(x0, torch::randn_like(x0) * used, t);
    const at::Tensor predicted = model->forward(x_t, t, model->caption_condition(captions, drop), skeletons, {}, true);
    const at::Tensor loss = diffusion::denoising_loss(predicted, x0, used, 8);
    optimizer.zero_grad();
    loss.backward();
    optimizer.step();
    if (step == 0) first = loss.item<double>();
    last = loss.item<double>();
  }
  EXPECT_LT(last, 0.5 * first);
  // Trained, the samples swing about as far as the real motions do.
  const diffusion::SampledTurning trained = sample_and_measure();
  std::printf("trained: pose kept %.3f, speed kept %.3f\n", trained.pose_kept(), trained.speed_kept());
  // Guidance 2 swings a little wider than the data: 1.27 and 1.29 seen (deterministic here); the bounds leave
  // room for other BLAS roundings, not for a model that half stands still.
  EXPECT_GT(trained.pose_kept(), 0.9);
  EXPECT_LT(trained.pose_kept(), 1.6);
  EXPECT_GT(trained.speed_kept(), 0.9);
  EXPECT_LT(trained.speed_kept(), 1.6);
  at::Tensor conditions;
  {
    torch::NoGradGuard no_grad;
    conditions = model->caption_condition(piece_batch({{2}, {3}}), {});
  }
  int right = 0;
  for (int64_t c = 0; c < 2; ++c) {
    const auto samples = diffusion::sample_motions(*model, schedule, one, conditions.narrow(0, c, 1), {8}, 4, options);
    for (const at::Tensor& sample : samples) {
      const at::Tensor swing = sample.select(1, 1).select(1, 4);
      const double to_a = (swing - a.select(1, 1).select(1, 4)).abs().mean().item<double>();
      const double to_b = (swing - b.select(1, 1).select(1, 4)).abs().mean().item<double>();
      right += (c == 0) == (to_a < to_b);
    }
  }
  EXPECT_GE(right, 7) << "samples closer to their own caption's motion, of 8";
}

TEST(DiffusionTrainConfig, TheShippedConfigsReadAndWriteBackTheirOwnValues) {
  for (const std::string name : {"diffusion_pose_cpu", "diffusion_motion_cpu", "diffusion_pose_gpu", "diffusion_motion_gpu"}) {
    const std::string path = (std::filesystem::path(__FILE__).parent_path().parent_path() / "configs" / (name + ".json")).string();
    const nlohmann::json file = nlohmann::json::parse(read_file(path));
    const diffusion::DiffusionTrainConfig config = diffusion::read_diffusion_train_config(path);
    EXPECT_NO_THROW(config.validate()) << name;
    // The motion stage takes its model from the pose stage: its configs name none.
    EXPECT_EQ(file.contains("model"), name.find("pose") != std::string::npos) << name;
    const nlohmann::json written = train::write_config(config), given = file.flatten();
    for (auto it = given.begin(); it != given.end(); ++it) {
      if (it.key().find("comment") != std::string::npos) continue;
      EXPECT_EQ(written.at(nlohmann::json::json_pointer(it.key())), it.value()) << name << " " << it.key();
    }
  }
}

}  // namespace
}  // namespace nec

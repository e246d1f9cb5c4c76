// The shared optimizer setup: the warm-up + cosine schedule, its resumed end, clipping and non-finite steps.
#include "nec/train/optimizer.h"

#include "nec/motion/error.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace nec::train {
namespace {

OptimizerConfig schedule_config() {
  OptimizerConfig config;
  config.learning_rate = 1e-3;
  config.warmup_steps = 10;
  config.final_lr_fraction = 0.1;
  return config;
}

TEST(TrainSchedule, WarmsUpThenFollowsACosineToTheFinalRate) {
  const LearningRateSchedule schedule(schedule_config(), 110);
  const double tolerance = 1e-12;
  EXPECT_NEAR(schedule.at(1), 1e-4, tolerance);
  EXPECT_NEAR(schedule.at(10), 1e-3, tolerance);
  EXPECT_NEAR(schedule.at(60), 0.55e-3, tolerance);  // halfway down the cosine
  EXPECT_NEAR(schedule.at(110), 1e-4, tolerance);    // the last step runs at the final rate
  EXPECT_NEAR(schedule.at(500), 1e-4, tolerance);    // past the end: the floor
  for (int64_t step = 11; step < 110; ++step) EXPECT_LE(schedule.at(step + 1), schedule.at(step));
}

TEST(TrainSchedule, AMovedEndContinuesFromTheRateAtTheResumeStep) {
  LearningRateSchedule schedule(schedule_config(), 110);
  const double at_resume = schedule.at(60);
  schedule.change_end(60, 210);
  double largest_jump = 0.0;
  for (int64_t step = 50; step < 210; ++step) {
    largest_jump = std::max(largest_jump, std::abs(schedule.at(step + 1) - schedule.at(step)));
  }
  std::printf("largest step-to-step change around the moved end: %.3g (rate at the resume step %.3g)\n", largest_jump,
              at_resume);
  EXPECT_DOUBLE_EQ(schedule.at(60), at_resume);  // steps before the change keep their rates
  EXPECT_LT(largest_jump, 0.02 * 1e-3);          // no jump: a 150-step cosine from 0.55e-3 moves < 1e-5 a step
  EXPECT_NEAR(schedule.at(135), 1e-4 + (at_resume - 1e-4) * 0.5, 1e-12);  // halfway down the new cosine
  EXPECT_NEAR(schedule.at(210), 1e-4, 1e-12);
  EXPECT_EQ(schedule.total_steps(), 210);

  // Stored and read back, the schedule is the same.
  const LearningRateSchedule back = LearningRateSchedule::from_json(schedule_config(), schedule.to_json());
  for (int64_t step = 1; step <= 220; ++step) EXPECT_DOUBLE_EQ(back.at(step), schedule.at(step)) << step;
  // A resumed run that ends where the schedule ends keeps it; one that ends later moves it.
  const LearningRateSchedule same = LearningRateSchedule::resumed(schedule_config(), schedule.to_json(), 100, 210, "t");
  EXPECT_DOUBLE_EQ(same.at(150), schedule.at(150));
  const LearningRateSchedule longer = LearningRateSchedule::resumed(schedule_config(), schedule.to_json(), 100, 300, "t");
  EXPECT_DOUBLE_EQ(longer.at(100), schedule.at(100));
  EXPECT_GT(longer.at(200), schedule.at(200));
  EXPECT_THROW(LearningRateSchedule::resumed(schedule_config(), nlohmann::json::array(), 1, 2, "t"), InputError);
}

TEST(TrainSchedule, AnEndMovedDuringWarmUpOnlyStretchesTheDecay) {
  LearningRateSchedule moved(schedule_config(), 110);
  moved.change_end(5, 210);
  const LearningRateSchedule fresh(schedule_config(), 210);
  for (int64_t step = 1; step <= 210; ++step) EXPECT_DOUBLE_EQ(moved.at(step), fresh.at(step)) << step;
  EXPECT_THROW(moved.change_end(20, 20), std::invalid_argument);
  EXPECT_THROW(moved.change_end(4, 300), std::invalid_argument);  // before the last change
}

TEST(TrainSchedule, BadConfigsNameTheField) {
  OptimizerConfig config;
  config.learning_rate = 0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config = {};
  config.final_lr_fraction = 1.5;
  try {
    config.validate();
    FAIL() << "accepted final_lr_fraction 1.5";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("final_lr_fraction"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LearningRateSchedule(OptimizerConfig{}, 0), std::invalid_argument);
}

TEST(TrainOptimizerStep, ClipsTheGlobalNormAndSkipsNonFiniteGradients) {
  torch::manual_seed(0);
  at::Tensor a = torch::zeros({3}, torch::requires_grad()), b = torch::zeros({4}, torch::requires_grad());
  OptimizerConfig config;
  config.weight_decay = 0.0;
  auto optimizer = make_adamw({a, b}, config);
  // Gradients (3, 4, 0) and (0, 0, 0, 12): global norm 13, clipped to 1.
  optimizer->zero_grad();
  (a * torch::tensor({3.f, 4.f, 0.f})).sum().backward();
  (b * torch::tensor({0.f, 0.f, 0.f, 12.f})).sum().backward();
  const OptimizerStep step = optimizer_step(*optimizer, {a, b}, 1.0, 0.01);
  EXPECT_TRUE(step.taken);
  EXPECT_NEAR(step.grad_norm, 13.0, 1e-5);
  const double clipped = std::sqrt(a.grad().pow(2).sum().item<double>() + b.grad().pow(2).sum().item<double>());
  EXPECT_NEAR(clipped, 1.0, 1e-5);
  EXPECT_NEAR(optimizer->param_groups()[0].options().get_lr(), 0.01, 1e-15);
  // Adam's first step moves each parameter with a non-zero gradient by the learning rate against its sign.
  EXPECT_NEAR(a[0].item<double>(), -0.01, 1e-6);
  EXPECT_NEAR(b[3].item<double>(), -0.01, 1e-6);
  EXPECT_EQ(a[2].item<double>(), 0.0);

  const at::Tensor before = b.detach().clone();
  optimizer->zero_grad();
  (b * torch::tensor({0.f, std::nanf(""), 0.f, 1.f})).sum().backward();
  const OptimizerStep skipped = optimizer_step(*optimizer, {a, b}, 1.0, 0.01);
  EXPECT_FALSE(skipped.taken);
  EXPECT_TRUE(std::isnan(skipped.grad_norm));
  EXPECT_TRUE(torch::equal(b.detach(), before)) << "a NaN gradient must not move the parameters";
}

}  // namespace
}  // namespace nec::train

// AdamW, gradient clipping and the warm-up + cosine learning-rate schedule.
#include "nec/train/optimizer.h"

#include "nec/motion/error.h"
#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nec::train {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

// From `from` at progress 0 down to `to` at progress 1.
double cosine(double from, double to, double progress) {
  return to + (from - to) * 0.5 * (1.0 + std::cos(kPi * std::clamp(progress, 0.0, 1.0)));
}

}  // namespace

void OptimizerConfig::validate() const {
  require(std::isfinite(learning_rate) && learning_rate > 0.0, "learning_rate must be a positive number");
  require(final_lr_fraction >= 0.0 && final_lr_fraction <= 1.0, "final_lr_fraction must be in [0, 1]");
  require(warmup_steps >= 0, "warmup_steps must be >= 0");
  require(std::isfinite(weight_decay) && weight_decay >= 0.0, "weight_decay must be >= 0");
  require(std::isfinite(grad_clip) && grad_clip >= 0.0, "grad_clip must be >= 0 (0 = no clipping)");
}

void visit_fields(ConfigVisitor& v, OptimizerConfig& c) {
  v.field("learning_rate", c.learning_rate, "peak learning rate after warm-up");
  v.field("final_lr_fraction", c.final_lr_fraction, "rate at the last step, as a fraction of learning_rate");
  v.field("warmup_steps", c.warmup_steps, "steps of linear warm-up; 0 = none");
  v.field("weight_decay", c.weight_decay, "AdamW decoupled weight decay");
  v.field("grad_clip", c.grad_clip, "largest global gradient norm; 0 = no clipping");
}

LearningRateSchedule::LearningRateSchedule(const OptimizerConfig& config, int64_t total_steps)
    : config_(config), first_total_steps_(total_steps), base_end_(total_steps) {
  config_.validate();
  require(total_steps >= 1, "a training run needs total_steps >= 1, got " + std::to_string(total_steps));
}

double LearningRateSchedule::at(int64_t step) const {
  const double peak = config_.learning_rate, floor = peak * config_.final_lr_fraction;
  for (auto it = segments_.rbegin(); it != segments_.rend(); ++it) {
    if (step > it->begin) {
      return cosine(it->start_rate, floor, static_cast<double>(step - it->begin) / (it->end - it->begin));
    }
  }
  const int64_t warmup = config_.warmup_steps;
  if (warmup > 0 && step <= warmup) return peak * static_cast<double>(std::max<int64_t>(step, 1)) / warmup;
  return cosine(peak, floor, static_cast<double>(step - warmup) / std::max<int64_t>(base_end_ - warmup, 1));
}

void LearningRateSchedule::change_end(int64_t step, int64_t total_steps) {
  require(step >= 0 && total_steps > step, "a new end of the run (step " + std::to_string(total_steps) +
                                               ") must come after the step it is set at (" + std::to_string(step) + ")");
  require(end_changes_.empty() || step >= end_changes_.back().first,
          "the end of the run changes at step " + std::to_string(step) + ", before the last change");
  end_changes_.emplace_back(step, total_steps);
  if (step > config_.warmup_steps) {
    segments_.push_back(Segment{step, total_steps, at(step)});
  } else {
    base_end_ = total_steps;  // still warming up: the decay has not begun, only its end moves
  }
}

nlohmann::json LearningRateSchedule::to_json() const {
  nlohmann::json changes = nlohmann::json::array();
  for (const auto& [step, total] : end_changes_) changes.push_back({step, total});
  return {{"total_steps", first_total_steps_}, {"end_changes", changes}};
}

LearningRateSchedule LearningRateSchedule::from_json(const OptimizerConfig& config, const nlohmann::json& object) {
  require(object.is_object() && object.contains("total_steps") && object.at("total_steps").is_number_integer() &&
              object.contains("end_changes") && object.at("end_changes").is_array(),
          "a learning-rate schedule needs an integer total_steps and a list end_changes");
  LearningRateSchedule schedule(config, object.at("total_steps").get<int64_t>());
  for (const nlohmann::json& change : object.at("end_changes")) {
    require(change.is_array() && change.size() == 2 && change[0].is_number_integer() && change[1].is_number_integer(),
            "each of end_changes must be [step, total_steps]");
    schedule.change_end(change[0].get<int64_t>(), change[1].get<int64_t>());
  }
  return schedule;
}

LearningRateSchedule LearningRateSchedule::resumed(const OptimizerConfig& config, const nlohmann::json& stored,
                                                   int64_t step, int64_t total_steps, const std::string& file) {
  try {
    LearningRateSchedule schedule = from_json(config, stored);
    if (total_steps != schedule.total_steps() && total_steps > step) schedule.change_end(step, total_steps);
    return schedule;
  } catch (const std::invalid_argument& e) {
    throw InputError(file, 0, std::string("field 'schedule': ") + e.what() + "; the training state is damaged");
  }
}

std::unique_ptr<torch::optim::AdamW> make_adamw(const std::vector<at::Tensor>& parameters,
                                                const OptimizerConfig& config) {
  config.validate();
  return std::make_unique<torch::optim::AdamW>(
      parameters, torch::optim::AdamWOptions(config.learning_rate).weight_decay(config.weight_decay));
}

OptimizerStep optimizer_step(torch::optim::Optimizer& optimizer, const std::vector<at::Tensor>& parameters,
                             double max_grad_norm, double learning_rate, const Communicator* communicator) {
  std::vector<at::Tensor> gradients;
  for (const at::Tensor& parameter : parameters) {
    if (communicator != nullptr && parameter.requires_grad() && !parameter.grad().defined()) {
      parameter.mutable_grad() = torch::zeros_like(parameter);  // every rank sums the same list
    }
    if (parameter.grad().defined()) gradients.push_back(parameter.grad());
  }
  if (communicator != nullptr) communicator->sum(gradients);
  OptimizerStep out;
  if (!gradients.empty()) {
    std::vector<at::Tensor> norms;
    norms.reserve(gradients.size());
    for (const at::Tensor& gradient : gradients) norms.push_back(gradient.detach().norm().reshape({1}));
    out.grad_norm = torch::cat(norms).norm().item<double>();
  }
  if (!std::isfinite(out.grad_norm)) {
    optimizer.zero_grad();
    return out;
  }
  if (max_grad_norm > 0.0 && out.grad_norm > max_grad_norm) {
    torch::NoGradGuard no_grad;
    const double scale = max_grad_norm / (out.grad_norm + 1e-6);
    for (at::Tensor& gradient : gradients) gradient.mul_(scale);
  }
  for (auto& group : optimizer.param_groups()) group.options().set_lr(learning_rate);
  optimizer.step();
  out.taken = true;
  return out;
}

}  // namespace nec::train

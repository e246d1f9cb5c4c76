// The one optimizer setup every trainer uses: AdamW with decoupled weight
// decay, global gradient-norm clipping, and a learning-rate schedule of
// linear warm-up then cosine decay to a fraction of the peak.
//
//   OptimizerConfig config;                       // learning_rate 1e-3, warmup 100, cosine to 0.1 x
//   auto adamw = make_adamw(model->parameters(), config);
//   LearningRateSchedule schedule(config, 2000);  // a run of steps 1..2000
//   for (int64_t step = 1; step <= 2000; ++step) {
//     adamw->zero_grad();
//     loss(step).backward();
//     const OptimizerStep taken = optimizer_step(*adamw, model->parameters(), config.grad_clip,
//                                                schedule.at(step));
//   }
//
// Steps count from 1: step s runs at schedule.at(s); the last step of the run
// runs at the final rate exactly.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace at {
class Tensor;
}
namespace torch::optim {
class AdamW;
class Optimizer;
}  // namespace torch::optim

namespace nec::train {

class Communicator;
class ConfigVisitor;

struct OptimizerConfig {
  double learning_rate = 1e-3;     // peak rate after warm-up, e.g. 1e-3 (small CPU models), 2e-4 (paper size)
  double final_lr_fraction = 0.1;  // the rate at the last step, as a fraction of learning_rate, e.g. 0.1
  int64_t warmup_steps = 100;      // linear warm-up from learning_rate / warmup_steps, e.g. 100; 0 = none
  double weight_decay = 0.01;      // AdamW decoupled weight decay, e.g. 0.01
  double grad_clip = 1.0;          // largest global gradient norm; 0 = no clipping

  // Throws std::invalid_argument naming the field, e.g. "learning_rate must be a positive number".
  void validate() const;
};
// The field list of an "optimizer" object (config_fields.h).
void visit_fields(ConfigVisitor& v, OptimizerConfig& c);

// The learning rate of every step of a run. A run resumed with a new end
// (`--resume --steps N`) does not jump: from the step it resumes at, the rate
// goes on from where it was and decays by a cosine to the final rate at the
// new end (while still warming up, only the end moves; warm-up does not depend on it).
class LearningRateSchedule {
 public:
  // Steps 1..total_steps. Throws std::invalid_argument for a bad config or total_steps < 1.
  LearningRateSchedule(const OptimizerConfig& config, int64_t total_steps);

  // The rate of step `step` (1-based); past the end: the final rate.
  double at(int64_t step) const;
  // The end now: the last end change's, else the one the run began with.
  int64_t total_steps() const { return end_changes_.empty() ? first_total_steps_ : end_changes_.back().second; }
  // From `step` on, the run ends at `total_steps` (> step). Throws std::invalid_argument otherwise.
  void change_end(int64_t step, int64_t total_steps);

  // {"total_steps": 2000, "end_changes": [[1500, 3000], ...]}: what a training state stores.
  nlohmann::json to_json() const;
  // The schedule `to_json` wrote, for `config`; throws std::invalid_argument for a malformed object.
  static LearningRateSchedule from_json(const OptimizerConfig& config, const nlohmann::json& object);
  // The schedule a run resumed at `step` goes on with: the stored one, its end
  // moved to `total_steps` when that differs (and lies after `step`). Throws
  // InputError naming `file` for a malformed stored schedule.
  static LearningRateSchedule resumed(const OptimizerConfig& config, const nlohmann::json& stored, int64_t step,
                                      int64_t total_steps, const std::string& file);

 private:
  struct Segment {
    int64_t begin = 0;       // first step of the segment is begin + 1
    int64_t end = 0;         // its last step
    double start_rate = 0;   // the rate at step `begin` that the cosine starts from
  };

  OptimizerConfig config_;
  int64_t first_total_steps_ = 0;  // the end the run began with
  int64_t base_end_ = 0;           // the end of the first cosine
  std::vector<Segment> segments_;  // decays after end changes, in step order
  std::vector<std::pair<int64_t, int64_t>> end_changes_;  // (step, new end), in step order
};

// AdamW over `parameters` with the config's peak rate and weight decay.
std::unique_ptr<torch::optim::AdamW> make_adamw(const std::vector<at::Tensor>& parameters,
                                                const OptimizerConfig& config);

struct OptimizerStep {
  double grad_norm = 0.0;  // global norm of the gradients before clipping (averaged over ranks)
  bool taken = false;      // false when the norm was NaN or infinite: no update, gradients zeroed
};

// After backward: sums the gradients over the ranks of `communicator` (null:
// one process; each rank weights its loss by its share of the global batch,
// so the sum is the whole batch's gradient), measures their global norm, and,
// when it is finite, clips it to `max_grad_norm` (0: no clipping), sets
// `learning_rate` and takes one optimizer step. Every rank takes the same step.
OptimizerStep optimizer_step(torch::optim::Optimizer& optimizer, const std::vector<at::Tensor>& parameters,
                             double max_grad_norm, double learning_rate, const Communicator* communicator = nullptr);

}  // namespace nec::train

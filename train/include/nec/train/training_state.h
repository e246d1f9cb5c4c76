// The training state of a checkpoint: what `--resume` needs beyond the model,
// the same two files for every model, written into the checkpoint directory
// (checkpoint_io.h) next to the model's own files:
//
//   training.json  {"format": "nec-training", "version": 1, "model": "tat", "step": 1200,
//                   "config": {...the run's whole config...},
//                   "schedule": {"total_steps": 1500, "end_changes": []},
//                   "data": {...the model's data record: loader position, caches, skeleton hashes...},
//                   "optimizer": "optimizer.pt"}
//   optimizer.pt   the optimizer's state (AdamW moments)
//
// Random draws need no stored generator: a step's draws come from (config
// seed, step) and the batch loader's from (seed, epoch, position), so a
// resumed run takes the steps of one that never stopped.
//
//   write_training_state(temp_dir, TrainingState{"tat", step, config_json, schedule.to_json(), data}, optimizer);
//   std::optional<TrainingState> state = read_training_state("runs/tat", "tat");
//   check_resumable(*state, config_json, {"steps", "log_every"}, "runs/tat/training.json");
//   load_optimizer_state("runs/tat", optimizer, device);
#pragma once

#include <c10/core/Device.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace torch::optim {
class Optimizer;
}

namespace nec::train {

constexpr const char* kTrainingStateFormat = "nec-training";  // training.json "format"
constexpr int kTrainingStateVersion = 1;                      // training.json "version"
constexpr const char* kTrainingStateFile = "training.json";
constexpr const char* kOptimizerStateFile = "optimizer.pt";

struct TrainingState {
  std::string model;                                  // which trainer wrote it, e.g. "owo", "tat"
  int64_t step = 0;                                   // optimizer steps taken
  nlohmann::json config = nlohmann::json::object();   // the run's config, as the trainer writes it
  nlohmann::json schedule = nlohmann::json::object(); // LearningRateSchedule::to_json
  nlohmann::json data = nlohmann::json::object();     // the trainer's data record
};

// training.json and optimizer.pt into `dir` (a checkpoint's temporary directory).
void write_training_state(const std::string& dir, const TrainingState& state, torch::optim::Optimizer& optimizer);

// The state in `dir`, or std::nullopt when it has no training.json (a model
// not written by `nec train`). Throws InputError naming the file for a damaged
// file, another format or version, or a state of another model than `model`.
std::optional<TrainingState> read_training_state(const std::string& dir, const std::string& model);

// The state a `--resume` of `nec train MODEL` needs from checkpoint `dir`: as
// read_training_state, and InputError when there is none or its step is not
// `model_step` (the step the model files of the checkpoint say).
TrainingState resumable_state(const std::string& dir, const std::string& model, int64_t model_step);

// Loads optimizer.pt of `dir` into `optimizer` (tensors onto `device`); InputError naming the file when it fails.
void load_optimizer_state(const std::string& dir, torch::optim::Optimizer& optimizer, const c10::Device& device);

// The dotted fields whose values differ between two configs, e.g.
// {"optimizer.learning_rate"} (list indices dropped), leaving out `may_change`.
std::vector<std::string> differing_fields(const nlohmann::json& a, const nlohmann::json& b,
                                          const std::set<std::string>& may_change);

// Throws InputError(file, 0, ...) listing every field (with both values) in
// which `now` differs from the state's config, apart from `may_change`.
void check_resumable(const TrainingState& state, const nlohmann::json& now, const std::set<std::string>& may_change,
                     const std::string& file);

}  // namespace nec::train

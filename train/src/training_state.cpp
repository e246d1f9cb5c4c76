// training.json + optimizer.pt: the resumable state of a training run, and config differences.
#include "nec/train/training_state.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/train/checkpoint_io.h"

#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <map>

namespace nec::train {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// Dotted name of a flattened JSON pointer, list indices dropped: "/data/held_out/0" -> "data.held_out".
std::string dotted(const std::string& pointer) {
  std::string out;
  size_t start = 1;
  while (start <= pointer.size()) {
    size_t end = pointer.find('/', start);
    if (end == std::string::npos) end = pointer.size();
    const std::string part = pointer.substr(start, end - start);
    const bool index = !part.empty() && std::all_of(part.begin(), part.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!index && !part.empty()) out += (out.empty() ? "" : ".") + part;
    start = end + 1;
  }
  return out;
}

// The value of a dotted field as JSON text, "absent" when there is none.
std::string value_text(const json& root, const std::string& field) {
  std::string pointer = "/" + field;
  std::replace(pointer.begin(), pointer.end(), '.', '/');
  const json::json_pointer at(pointer);
  return root.contains(at) ? root.at(at).dump() : std::string("absent");
}

}  // namespace

void write_training_state(const std::string& dir, const TrainingState& state, torch::optim::Optimizer& optimizer) {
  const json record = {{"format", kTrainingStateFormat}, {"version", kTrainingStateVersion},
                       {"model", state.model},           {"step", state.step},
                       {"config", state.config},         {"schedule", state.schedule},
                       {"data", state.data},             {"optimizer", kOptimizerStateFile}};
  write_file_atomic((fs::path(dir) / kTrainingStateFile).string(), record.dump(2) + "\n");
  try {
    torch::save(optimizer, (fs::path(dir) / kOptimizerStateFile).string());
  } catch (const c10::Error& e) {
    throw std::runtime_error(dir + ": cannot write the optimizer state: " + first_line(e.what()));
  }
}

std::optional<TrainingState> read_training_state(const std::string& dir, const std::string& model) {
  const std::string path = (fs::path(dir) / kTrainingStateFile).string();
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  const std::string hint = "the training state is damaged; train again into a new --out";
  const JsonFields fields(path, hint);
  json root;
  try {
    root = json::parse(read_file(path, size_t{1} << 26));
  } catch (const json::parse_error& e) {
    fields.fail(std::string("not valid JSON (") + e.what() + "); " + hint);
  }
  if (!root.is_object()) fields.fail("not a training state (no JSON object); " + hint);
  std::string format;
  fields.read(root, "format", "", format);
  if (format != kTrainingStateFormat) fields.fail("format '" + format + "' is not " + kTrainingStateFormat + "; " + hint);
  int64_t version = 0;
  fields.read(root, "version", "", version);
  if (version != kTrainingStateVersion) {
    fields.fail("was written by format version " + std::to_string(version) + "; this nec reads version " +
                std::to_string(kTrainingStateVersion) + ": resume with the nec that wrote it, or train into a new --out");
  }
  TrainingState state;
  fields.read(root, "model", "", state.model);
  if (state.model != model) {
    fields.fail("is the training state of a '" + state.model + "' model, not '" + model +
                "'; give the --out of a `nec train " + model + "` run");
  }
  fields.read(root, "step", "", state.step);
  state.config = fields.object(root, "config", "");
  state.schedule = fields.object(root, "schedule", "");
  state.data = fields.object(root, "data", "");
  return state;
}

TrainingState resumable_state(const std::string& dir, const std::string& model, int64_t model_step) {
  const std::string path = (fs::path(dir) / kTrainingStateFile).string();
  std::optional<TrainingState> state = read_training_state(dir, model);
  if (!state) {
    throw InputError(path, 0,
                     "missing: not a checkpoint written by `nec train " + model +
                         "`, nothing to resume; train into a new --out");
  }
  if (state->step != model_step) {
    throw InputError(path, 0,
                     "step " + std::to_string(state->step) + " but config.json says " + std::to_string(model_step) +
                         "; the checkpoint is damaged");
  }
  return std::move(*state);
}

void load_optimizer_state(const std::string& dir, torch::optim::Optimizer& optimizer, const c10::Device& device) {
  const std::string path = (fs::path(dir) / kOptimizerStateFile).string();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, 0, "missing; the checkpoint is incomplete, cannot resume");
  try {
    torch::serialize::InputArchive archive;
    archive.load_from(path, device);
    optimizer.load(archive);
  } catch (const c10::Error& e) {
    throw InputError(path, 0, "cannot read the optimizer state: " + first_line(e.what()));
  }
}

std::vector<std::string> differing_fields(const json& a, const json& b, const std::set<std::string>& may_change) {
  const json flat_a = a.flatten(), flat_b = b.flatten();
  std::vector<std::string> out;
  auto note = [&](const std::string& pointer) {
    const std::string field = dotted(pointer);
    if (may_change.count(field) || std::find(out.begin(), out.end(), field) != out.end()) return;
    out.push_back(field);
  };
  for (auto it = flat_a.begin(); it != flat_a.end(); ++it) {
    const auto other = flat_b.find(it.key());
    if (other == flat_b.end() || *other != it.value()) note(it.key());
  }
  for (auto it = flat_b.begin(); it != flat_b.end(); ++it) {
    if (!flat_a.contains(it.key())) note(it.key());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void check_resumable(const TrainingState& state, const json& now, const std::set<std::string>& may_change,
                     const std::string& file) {
  const std::vector<std::string> changed = differing_fields(state.config, now, may_change);
  if (changed.empty()) return;
  std::string what;
  for (const std::string& field : changed) {
    what += (what.empty() ? "" : ", ") + std::string("'") + field + "' (checkpoint " + value_text(state.config, field) +
            ", now " + value_text(now, field) + ")";
  }
  std::string allowed;
  for (const std::string& field : may_change) allowed += (allowed.empty() ? "" : ", ") + field;
  throw InputError(file, 0,
                   "cannot resume: the config differs in " + what + "; resume with the config it was trained with " +
                       "(only " + allowed + " may change), or train into a new --out");
}

}  // namespace nec::train

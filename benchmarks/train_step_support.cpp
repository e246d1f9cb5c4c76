// The training-step benchmarks' record, counters and op profile.
#include "train_step_support.h"

#include <ATen/record_function.h>
#include <malloc.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <set>
#include <stdexcept>
#include <utility>
#include <vector>

namespace nec::bench {
namespace {

using Clock = std::chrono::steady_clock;

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// One open record: when it started and the time of the records nested in it.
struct OpenRecord : at::ObserverContext {
  Clock::time_point start;
  double nested_ms = 0;
};

// The profile being filled (one at a time: callbacks are plain functions).
std::mutex profile_mutex;
OpProfile* active = nullptr;
thread_local std::vector<OpenRecord*> open_records;

std::unique_ptr<at::ObserverContext> on_start(const at::RecordFunction&) {
  auto record = std::make_unique<OpenRecord>();
  open_records.push_back(record.get());
  record->start = Clock::now();
  return record;
}

void on_end(const at::RecordFunction& fn, at::ObserverContext* context) {
  const Clock::time_point end = Clock::now();
  auto* record = static_cast<OpenRecord*>(context);
  const double total = ms_between(record->start, end);
  if (!open_records.empty() && open_records.back() == record) open_records.pop_back();
  const bool top_level = open_records.empty();
  if (!top_level) open_records.back()->nested_ms += total;
  std::lock_guard<std::mutex> lock(profile_mutex);
  if (active == nullptr) return;
  OpTime& op = active->ops[fn.name()];
  op.calls += 1;
  op.total_ms += total;
  op.self_ms += total - record->nested_ms;
  if (top_level) active->top_level_ms += total;
}

std::string& profile_dir() {
  static std::string dir;
  return dir;
}

std::string& configs_dir_setting() {
  static std::string dir = std::string(NEC_SOURCE_DIR) + "/configs";
  return dir;
}

int64_t status_kib(const char* field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const size_t length = std::strlen(field);
  while (std::getline(status, line)) {
    if (line.compare(0, length, field) == 0) return std::stoll(line.substr(length + 1));
  }
  return -1;
}

}  // namespace

PeakRss measure_peak_rss(const std::function<void()>& region) {
  malloc_trim(0);
  std::ofstream("/proc/self/clear_refs") << "5";
  const int64_t start = status_kib("VmRSS:");
  region();
  const int64_t peak = status_kib("VmHWM:");
  PeakRss out;
  if (start >= 0 && peak >= 0) {
    out.above_start_mib = static_cast<double>(peak - start) / 1024.0;
    out.peak_mib = static_cast<double>(peak) / 1024.0;
  }
  return out;
}

StepRecord record_first_steps(const std::vector<at::Tensor>& parameters, const std::function<double()>& step) {
  StepRecord record;
  for (const at::Tensor& p : parameters) record.parameters += p.numel();
  for (int64_t i = 0; i < kWarmupSteps; ++i) record.first_losses.push_back(step());
  record.memory = measure_peak_rss([&] { benchmark::DoNotOptimize(step()); });
  return record;
}

void set_step_counters(benchmark::State& state, const StepRecord& record) {
  state.counters["parameters"] = static_cast<double>(record.parameters);
  state.counters["loss_step0"] = record.first_losses.at(0);
  state.counters["loss_step1"] = record.first_losses.at(1);
  state.counters["step_peak_MiB"] = record.memory.above_start_mib;
  state.counters["rss_peak_MiB"] = record.memory.peak_mib;
}

double smallest(const std::vector<double>& values) { return *std::min_element(values.begin(), values.end()); }
double largest(const std::vector<double>& values) { return *std::max_element(values.begin(), values.end()); }

OpProfile profile_ops(const std::function<void()>& region, int64_t repeats) {
  OpProfile profile;
  profile.repeats = repeats;
  {
    std::lock_guard<std::mutex> lock(profile_mutex);
    active = &profile;
  }
  const at::CallbackHandle handle = at::addGlobalCallback(
      at::RecordFunctionCallback(on_start, on_end).scopes({at::RecordScope::FUNCTION, at::RecordScope::BACKWARD_FUNCTION}));
  const Clock::time_point start = Clock::now();
  for (int64_t i = 0; i < repeats; ++i) region();
  profile.wall_ms = ms_between(start, Clock::now());
  at::removeCallback(handle);
  std::lock_guard<std::mutex> lock(profile_mutex);
  active = nullptr;
  return profile;
}

void write_op_profile(const OpProfile& profile, const std::string& path) {
  nlohmann::json out = {{"repeats", profile.repeats}, {"wall_ms", profile.wall_ms},
                        {"top_level_ms", profile.top_level_ms}, {"ops", nlohmann::json::object()}};
  for (const auto& [name, op] : profile.ops) {
    out["ops"][name] = {{"calls", op.calls}, {"self_ms", op.self_ms}, {"total_ms", op.total_ms}};
  }
  std::ofstream file(path);
  if (!(file << out.dump(1) << '\n')) throw std::runtime_error("cannot write " + path);
}

const std::string& configs_dir() { return configs_dir_setting(); }

bool take_step_flag(const char* arg) {
  for (const auto& [flag, value] : {std::pair<const char*, std::string*>{"--profile_ops=", &profile_dir()},
                                    std::pair<const char*, std::string*>{"--configs=", &configs_dir_setting()}}) {
    if (std::strncmp(arg, flag, std::strlen(flag)) == 0) {
      *value = arg + std::strlen(flag);
      return true;
    }
  }
  return false;
}

void profile_ops_if_asked(const std::string& label, const std::function<void()>& region, int64_t repeats) {
  static std::set<std::string> profiled;  // a benchmark body runs once per repetition; one profile is enough
  if (profile_dir().empty() || !profiled.insert(label).second) return;
  std::string file = label;
  for (char& c : file) {
    if (c == '/' || c == ':') c = '_';
  }
  std::filesystem::create_directories(profile_dir());
  write_op_profile(profile_ops(region, repeats), profile_dir() + "/" + file + ".json");
}

}  // namespace nec::bench

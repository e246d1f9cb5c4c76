// OwO pretraining runs: config file, learning-rate schedule, batches, training checkpoints.
#include "nec/owo/training.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/checkpoint.h"
#include "nec/owo/checkpoint_io.h"
#include "nec/owo/graph.h"
#include "nec/owo/joint_names.h"

#include <c10/util/Exception.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <type_traits>

namespace nec::owo {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kRecordFile = "training.json";
constexpr const char* kOptimizerFile = "optimizer.pt";
constexpr double kPi = 3.14159265358979323846;
// Schedule fields a resumed run may change.
const std::set<std::string> kScheduleFields = {"steps", "log_every", "validate_every", "checkpoint_every"};

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

uint64_t mix(uint64_t x) {  // splitmix64 finalizer
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// Reads an object of a config file: optional fields with checked types, and
// no field it does not know.
class ConfigFields {
 public:
  ConfigFields(const std::string& file, const json& object, std::string prefix, std::initializer_list<const char*> known)
      : file_(file), object_(object), prefix_(std::move(prefix)) {
    if (!object_.is_object()) fail_field(prefix_.empty() ? "(top level)" : prefix_.substr(0, prefix_.size() - 1), "must be an object");
    std::string known_list;
    for (const char* k : known) known_list += (known_list.empty() ? "" : ", ") + std::string(k);
    for (auto it = object_.begin(); it != object_.end(); ++it) {
      bool found = false;
      for (const char* k : known) found = found || it.key() == k;
      if (!found) fail(prefix_ + it.key(), "is not a known field (known here: " + known_list + ")");
    }
  }

  template <typename T>
  void read(const char* key, T& out) const {
    const auto it = object_.find(key);
    if (it == object_.end()) return;
    const json& value = *it;
    const std::string name = prefix_ + key;
    if constexpr (std::is_same_v<T, bool>) {
      if (!value.is_boolean()) fail_field(name, "must be true or false");
      out = value.get<bool>();
    } else if constexpr (std::is_same_v<T, uint64_t>) {
      if (!value.is_number_unsigned()) fail_field(name, "must be a non-negative integer");
      out = value.get<uint64_t>();
    } else if constexpr (std::is_integral_v<T>) {
      if (!value.is_number_integer()) fail_field(name, "must be an integer");
      const int64_t v = value.get<int64_t>();
      if (v < std::numeric_limits<T>::min() || v > std::numeric_limits<T>::max()) fail_field(name, "is out of range");
      out = static_cast<T>(v);
    } else if constexpr (std::is_floating_point_v<T>) {
      if (!value.is_number()) fail_field(name, "must be a number");
      out = value.get<double>();
    } else {
      if (!value.is_array()) fail_field(name, "must be a list of strings");
      out.clear();
      for (const json& item : value) {
        if (!item.is_string()) fail_field(name, "must be a list of strings");
        out.push_back(item.get<std::string>());
      }
    }
  }

  // A nested object, or an empty one when absent.
  const json& object(const char* key) const {
    static const json kEmpty = json::object();
    const auto it = object_.find(key);
    return it == object_.end() ? kEmpty : *it;
  }

  [[noreturn]] void fail_field(const std::string& name, const std::string& problem) const {
    fail(name, problem);
  }

 private:
  [[noreturn]] void fail(const std::string& name, const std::string& problem) const {
    throw InputError(file_, 0, "field '" + name + "' " + problem);
  }

  const std::string& file_;
  const json& object_;
  std::string prefix_;
};

OwoTrainingConfig config_from_json(const json& root, const std::string& file) {
  OwoTrainingConfig c;
  const ConfigFields top(file, root, "",
                         {"encoder", "pretrain", "optimizer", "data", "names", "batch_size", "batch_joint_pairs", "steps", "log_every",
                          "validate_every", "checkpoint_every", "seed"});
  top.read("names", c.names);
  top.read("batch_size", c.batch_size);
  top.read("batch_joint_pairs", c.batch_joint_pairs);
  top.read("steps", c.steps);
  top.read("log_every", c.log_every);
  top.read("validate_every", c.validate_every);
  top.read("checkpoint_every", c.checkpoint_every);
  top.read("seed", c.seed);

  const ConfigFields encoder(file, top.object("encoder"), "encoder.",
                             {"graph", "name_dim", "dim", "layers", "heads", "edge_dim", "ffn_mult", "leaky_slope",
                              "tree_edges_only"});
  const ConfigFields graph(file, encoder.object("graph"), "encoder.graph.",
                           {"normalize_scale", "position_frequencies", "depth_scale", "children_scale",
                            "max_tree_distance"});
  graph.read("normalize_scale", c.encoder.graph.normalize_scale);
  graph.read("position_frequencies", c.encoder.graph.position_frequencies);
  graph.read("depth_scale", c.encoder.graph.depth_scale);
  graph.read("children_scale", c.encoder.graph.children_scale);
  graph.read("max_tree_distance", c.encoder.graph.max_tree_distance);
  encoder.read("name_dim", c.encoder.name_dim);
  encoder.read("dim", c.encoder.dim);
  encoder.read("layers", c.encoder.layers);
  encoder.read("heads", c.encoder.heads);
  encoder.read("edge_dim", c.encoder.edge_dim);
  encoder.read("ffn_mult", c.encoder.ffn_mult);
  encoder.read("leaky_slope", c.encoder.leaky_slope);
  encoder.read("tree_edges_only", c.encoder.tree_edges_only);

  const ConfigFields pretrain(file, top.object("pretrain"), "pretrain.",
                              {"offset_loss", "pair_offset_loss", "lca_loss", "name_loss", "offset_weight",
                               "pair_offset_weight", "lca_weight", "name_weight", "pairs_per_skeleton", "temperature"});
  pretrain.read("offset_loss", c.pretrain.offset_loss);
  pretrain.read("pair_offset_loss", c.pretrain.pair_offset_loss);
  pretrain.read("lca_loss", c.pretrain.lca_loss);
  pretrain.read("name_loss", c.pretrain.name_loss);
  pretrain.read("offset_weight", c.pretrain.offset_weight);
  pretrain.read("pair_offset_weight", c.pretrain.pair_offset_weight);
  pretrain.read("lca_weight", c.pretrain.lca_weight);
  pretrain.read("name_weight", c.pretrain.name_weight);
  pretrain.read("pairs_per_skeleton", c.pretrain.pairs_per_skeleton);
  pretrain.read("temperature", c.pretrain.temperature);

  const ConfigFields optimizer(file, top.object("optimizer"), "optimizer.",
                               {"lr", "weight_decay", "warmup_steps", "final_lr_fraction", "grad_clip"});
  optimizer.read("lr", c.optimizer.lr);
  optimizer.read("weight_decay", c.optimizer.weight_decay);
  optimizer.read("warmup_steps", c.optimizer.warmup_steps);
  optimizer.read("final_lr_fraction", c.optimizer.final_lr_fraction);
  optimizer.read("grad_clip", c.optimizer.grad_clip);

  const ConfigFields data(file, top.object("data"), "data.",
                          {"held_out", "cache_held_out", "poses_per_skeleton", "size_buckets", "augment"});
  data.read("held_out", c.data.held_out);
  data.read("cache_held_out", c.data.cache_held_out);
  data.read("poses_per_skeleton", c.data.poses_per_skeleton);
  data.read("size_buckets", c.data.size_buckets);
  const ConfigFields augment(file, data.object("augment"), "data.augment.",
                             {"probability", "rest_pose", "bone_length", "min_bone_factor", "max_bone_factor",
                              "joint_removal", "subdivision", "joint_fraction"});
  AugmentOptions& a = c.data.augment;
  augment.read("probability", a.probability);
  augment.read("rest_pose", a.rest_pose);
  augment.read("bone_length", a.bone_length);
  augment.read("min_bone_factor", a.min_bone_factor);
  augment.read("max_bone_factor", a.max_bone_factor);
  augment.read("joint_removal", a.joint_removal);
  augment.read("subdivision", a.subdivision);
  augment.read("joint_fraction", a.joint_fraction);

  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(file, 0, e.what());
  }
  return c;
}

json config_to_json(const OwoTrainingConfig& c) {
  const AugmentOptions& a = c.data.augment;
  return {{"encoder",
           {{"graph",
             {{"normalize_scale", c.encoder.graph.normalize_scale},
              {"position_frequencies", c.encoder.graph.position_frequencies},
              {"depth_scale", c.encoder.graph.depth_scale},
              {"children_scale", c.encoder.graph.children_scale},
              {"max_tree_distance", c.encoder.graph.max_tree_distance}}},
            {"name_dim", c.encoder.name_dim},
            {"dim", c.encoder.dim},
            {"layers", c.encoder.layers},
            {"heads", c.encoder.heads},
            {"edge_dim", c.encoder.edge_dim},
            {"ffn_mult", c.encoder.ffn_mult},
            {"leaky_slope", c.encoder.leaky_slope},
            {"tree_edges_only", c.encoder.tree_edges_only}}},
          {"pretrain",
           {{"offset_loss", c.pretrain.offset_loss},
            {"pair_offset_loss", c.pretrain.pair_offset_loss},
            {"lca_loss", c.pretrain.lca_loss},
            {"name_loss", c.pretrain.name_loss},
            {"offset_weight", c.pretrain.offset_weight},
            {"pair_offset_weight", c.pretrain.pair_offset_weight},
            {"lca_weight", c.pretrain.lca_weight},
            {"name_weight", c.pretrain.name_weight},
            {"pairs_per_skeleton", c.pretrain.pairs_per_skeleton},
            {"temperature", c.pretrain.temperature}}},
          {"optimizer",
           {{"lr", c.optimizer.lr},
            {"weight_decay", c.optimizer.weight_decay},
            {"warmup_steps", c.optimizer.warmup_steps},
            {"final_lr_fraction", c.optimizer.final_lr_fraction},
            {"grad_clip", c.optimizer.grad_clip}}},
          {"data",
           {{"held_out", c.data.held_out},
            {"cache_held_out", c.data.cache_held_out},
            {"poses_per_skeleton", c.data.poses_per_skeleton},
            {"size_buckets", c.data.size_buckets},
            {"augment",
             {{"probability", a.probability},
              {"rest_pose", a.rest_pose},
              {"bone_length", a.bone_length},
              {"min_bone_factor", a.min_bone_factor},
              {"max_bone_factor", a.max_bone_factor},
              {"joint_removal", a.joint_removal},
              {"subdivision", a.subdivision},
              {"joint_fraction", a.joint_fraction}}}}},
          {"names", c.names},
          {"batch_size", c.batch_size},
          {"batch_joint_pairs", c.batch_joint_pairs},
          {"steps", c.steps},
          {"log_every", c.log_every},
          {"validate_every", c.validate_every},
          {"checkpoint_every", c.checkpoint_every},
          {"seed", c.seed}};
}

struct FieldDifference {
  std::string field;        // dotted, e.g. "optimizer.lr"
  std::string then, now;    // JSON values
};

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

std::vector<FieldDifference> differences(const OwoTrainingConfig& a, const OwoTrainingConfig& b) {
  const json json_a = config_to_json(a), json_b = config_to_json(b);
  const json flat_a = json_a.flatten(), flat_b = json_b.flatten();
  auto value_of = [](const json& root, const std::string& field) {
    std::string pointer = "/" + field;
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    const json::json_pointer at(pointer);
    return root.contains(at) ? root.at(at).dump() : std::string("absent");
  };
  std::map<std::string, FieldDifference> found;
  auto note = [&](const std::string& pointer) {
    const std::string field = dotted(pointer);
    if (kScheduleFields.count(field) || found.count(field)) return;
    found[field] = FieldDifference{field, value_of(json_a, field), value_of(json_b, field)};
  };
  for (auto it = flat_a.begin(); it != flat_a.end(); ++it) {
    const auto other = flat_b.find(it.key());
    if (other == flat_b.end() || *other != it.value()) note(it.key());
  }
  for (auto it = flat_b.begin(); it != flat_b.end(); ++it) {
    if (!flat_a.contains(it.key())) note(it.key());
  }
  std::vector<FieldDifference> out;
  for (auto& [field, difference] : found) out.push_back(std::move(difference));
  return out;
}

std::vector<std::string> string_list(const JsonFields& fields, const json& root, const std::string& key) {
  const json& value = root.contains(key) ? root.at(key) : json();
  if (!value.is_array()) fields.fail("field '" + key + "' must be a list of strings; " + fields.hint());
  std::vector<std::string> out;
  for (const json& item : value) {
    if (!item.is_string()) fields.fail("field '" + key + "' must be a list of strings; " + fields.hint());
    out.push_back(item.get<std::string>());
  }
  return out;
}

}  // namespace

void OwoOptimizerConfig::validate() const {
  require(std::isfinite(lr) && lr > 0.0, "optimizer.lr must be a positive number");
  require(weight_decay >= 0.0, "optimizer.weight_decay must be >= 0");
  require(warmup_steps >= 0, "optimizer.warmup_steps must be >= 0");
  require(final_lr_fraction >= 0.0 && final_lr_fraction <= 1.0, "optimizer.final_lr_fraction must be in [0, 1]");
  require(grad_clip >= 0.0, "optimizer.grad_clip must be >= 0 (0 = no clipping)");
}

void OwoDataConfig::validate() const {
  require(poses_per_skeleton >= 0 && poses_per_skeleton <= 1024, "data.poses_per_skeleton must be in [0, 1024]");
  require(size_buckets >= 1, "data.size_buckets must be >= 1");
  try {
    augment.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("data.augment: ") + e.what());
  }
}

void OwoTrainingConfig::validate() const {
  try {
    encoder.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("encoder: ") + e.what());
  }
  try {
    pretrain.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("pretrain: ") + e.what());
  }
  optimizer.validate();
  data.validate();
  require(names || encoder.name_dim == 0,
          "encoder.name_dim must be 0 when names is false (got " + std::to_string(encoder.name_dim) + ")");
  require(!names || encoder.name_dim > 0,
          "encoder.name_dim must be the word vectors' dimension (e.g. 100) when names is true");
  require(batch_size >= 1, "batch_size must be >= 1");
  require(batch_joint_pairs >= 0, "batch_joint_pairs must be >= 0 (0 = no limit)");
  require(steps >= 1, "steps must be >= 1");
  require(log_every >= 0, "log_every must be >= 0");
  require(validate_every >= 0, "validate_every must be >= 0");
  require(checkpoint_every >= 0, "checkpoint_every must be >= 0");
}

OwoTrainingConfig parse_owo_training_config(const std::string& text, const std::string& file) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(file, 0, std::string("not valid JSON: ") + e.what());
  }
  return config_from_json(root, file);
}

std::string owo_training_config_json(const OwoTrainingConfig& config) { return config_to_json(config).dump(2) + "\n"; }

std::vector<std::string> differing_fields(const OwoTrainingConfig& a, const OwoTrainingConfig& b) {
  std::vector<std::string> out;
  for (const FieldDifference& d : differences(a, b)) out.push_back(d.field);
  return out;
}

double learning_rate(const OwoOptimizerConfig& optimizer, int64_t step, int64_t total_steps) {
  const double peak = optimizer.lr;
  if (optimizer.warmup_steps > 0 && step <= optimizer.warmup_steps) {
    return peak * static_cast<double>(std::max<int64_t>(step, 1)) / optimizer.warmup_steps;
  }
  const double span = static_cast<double>(std::max<int64_t>(total_steps - optimizer.warmup_steps, 1));
  const double progress = std::clamp((step - optimizer.warmup_steps) / span, 0.0, 1.0);
  const double floor = peak * optimizer.final_lr_fraction;
  return floor + (peak - floor) * 0.5 * (1.0 + std::cos(kPi * progress));
}

SkeletonSet load_skeleton_set(const std::vector<std::string>& caches, const HoldOut& hold_out,
                              int64_t poses_per_skeleton, uint64_t seed) {
  std::vector<PretrainSkeleton> all;
  std::string names;
  for (const std::string& dir : caches) {
    const DatasetCache cache = read_cache(dir);
    for (PretrainSkeleton& s : skeletons_from_cache(cache, static_cast<int>(poses_per_skeleton), seed)) {
      all.push_back(std::move(s));
    }
    names += (names.empty() ? "" : ", ") + dir;
  }
  SkeletonSet set = split_skeleton_set(all, hold_out);
  if (!set.unmatched_patterns.empty()) {
    std::string patterns;
    for (const std::string& p : set.unmatched_patterns) patterns += (patterns.empty() ? "'" : ", '") + p + "'";
    throw InputError(names, 0,
                     "hold-out pattern " + patterns +
                         " matches no skeleton (patterns match a skeleton's name or hash, a dataset, a source path "
                         "or a word of one, e.g. 'spider' for nec zoo's c004_spider folders)");
  }
  return set;
}

c10::Device training_device(const std::string& name) {
  if (name == "cpu") return c10::Device(c10::kCPU);
  if (name.rfind("cuda", 0) != 0) {
    throw std::invalid_argument("unknown device '" + name + "' (known: cpu, cuda, cuda:N)");
  }
  c10::Device device(c10::kCPU);
  try {
    device = c10::Device(name);
  } catch (const c10::Error&) {
    throw std::invalid_argument("unknown device '" + name + "' (known: cpu, cuda, cuda:N)");
  }
  if (!torch::cuda::is_available()) {
    throw std::runtime_error("--device " + name + ": this nec's torch has no CUDA device (" +
                             "a CPU-only libtorch, or no GPU visible); use --device cpu");
  }
  if (device.has_index() && device.index() >= static_cast<int>(torch::cuda::device_count())) {
    throw std::runtime_error("--device " + name + ": only " + std::to_string(torch::cuda::device_count()) +
                             " CUDA device(s) visible");
  }
  return device;
}

std::optional<OwoTrainingRecord> read_owo_training_record(const std::string& dir) {
  const std::string path = (fs::path(dir) / kRecordFile).string();
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
  if (!root.is_object()) fields.fail("not a training record (no JSON object); " + hint);
  std::string format;
  fields.read(root, "format", "", format);
  if (format != kOwoTrainingFormat) {
    fields.fail("format '" + format + "' is not " + kOwoTrainingFormat + "; " + hint);
  }
  int64_t version = 0;
  fields.read(root, "version", "", version);
  if (version != kOwoTrainingVersion) {
    fields.fail("was written by format version " + std::to_string(version) + "; this nec reads version " +
                std::to_string(kOwoTrainingVersion));
  }
  OwoTrainingRecord record;
  fields.read(root, "step", "", record.step);
  record.config = config_from_json(fields.object(root, "config", ""), path);
  record.data = string_list(fields, root, "data");
  record.train_skeletons = string_list(fields, root, "train_skeletons");
  record.held_out_skeletons = string_list(fields, root, "held_out_skeletons");
  return record;
}

OwoTrainer::OwoTrainer(const OwoTrainingConfig& config, SkeletonSet skeletons, const text::WordVectors* vectors,
                       const c10::Device& device)
    : config_(config), skeletons_(std::move(skeletons)), vectors_(config.names ? vectors : nullptr), device_(device) {
  config_.validate();
  require(!skeletons_.train.empty(), "OwoTrainer: no training skeletons (all are held out?)");
  if (config_.names) {
    require(vectors_ != nullptr, "OwoTrainer: the config asks for names, but no word vectors were given");
    require(vectors_->dim() == config_.encoder.name_dim,
            "encoder.name_dim is " + std::to_string(config_.encoder.name_dim) + ", but the word vectors (" +
                vectors_->path() + ") are " + std::to_string(vectors_->dim()) + "-d");
  }
  torch::manual_seed(config_.seed);
  model_ = OwoPretrainer(config_.encoder, config_.pretrain);
  model_->to(device_);
  optimizer_ = std::make_unique<torch::optim::AdamW>(
      model_->parameters(),
      torch::optim::AdamWOptions(config_.optimizer.lr).weight_decay(config_.optimizer.weight_decay));

  // Buckets of similar joint counts: a batch pads to its largest skeleton.
  std::vector<size_t> order(skeletons_.train.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return skeletons_.train[a].skeleton.joint_count() < skeletons_.train[b].skeleton.joint_count();
  });
  const size_t bucket_count = std::min<size_t>(static_cast<size_t>(config_.data.size_buckets), order.size());
  for (size_t b = 0; b < bucket_count; ++b) {
    const size_t begin = order.size() * b / bucket_count, end = order.size() * (b + 1) / bucket_count;
    buckets_.emplace_back(order.begin() + begin, order.begin() + end);
  }
}

OwoTrainer::~OwoTrainer() = default;

at::Tensor OwoTrainer::names_of(const std::vector<std::string>& canonical_names) const {
  return vectors_ ? name_embeddings(*vectors_, canonical_names) : at::Tensor();
}

PretrainLosses OwoTrainer::step(int64_t step) {
  const uint64_t stream = mix(config_.seed ^ mix(static_cast<uint64_t>(step)));
  std::mt19937 rng(static_cast<uint32_t>(stream));
  const double lr = learning_rate(config_.optimizer, step, config_.steps);
  for (auto& group : optimizer_->param_groups()) group.options().set_lr(lr);

  // A bucket with probability proportional to its size, then skeletons uniformly within it.
  const size_t anchor = std::uniform_int_distribution<size_t>(0, skeletons_.train.size() - 1)(rng);
  size_t bucket = 0;
  for (size_t seen = 0; bucket < buckets_.size(); ++bucket) {
    seen += buckets_[bucket].size();
    if (anchor < seen) break;
  }
  const std::vector<size_t>& members = buckets_[std::min(bucket, buckets_.size() - 1)];
  std::uniform_int_distribution<size_t> pick(0, members.size() - 1);
  // Up to batch_size skeletons, fewer when B * Jmax^2 would pass batch_joint_pairs (at least one).
  std::vector<SkeletonGraph> graphs;
  int64_t largest = 0;
  for (int64_t b = 0; b < config_.batch_size; ++b) {
    const PretrainSkeleton& source = skeletons_.train[members[pick(rng)]];
    AugmentedSkeleton rig = augment_skeleton(source, config_.data.augment, rng);
    const int64_t joints = std::max<int64_t>(largest, rig.skeleton.joint_count());
    if (b > 0 && config_.batch_joint_pairs > 0 && (b + 1) * joints * joints > config_.batch_joint_pairs) break;
    largest = joints;
    graphs.push_back(make_skeleton_graph(rig.skeleton, names_of(rig.canonical_names), config_.encoder.graph));
  }
  const GraphBatch batch = collate(graphs, config_.encoder.name_dim).to(device_);
  torch::manual_seed(mix(stream) >> 1);  // the sampled joint pairs
  return model_->pretrain_step(batch, *optimizer_, config_.optimizer.grad_clip);
}

std::vector<SkeletonScore> OwoTrainer::score_held_out() {
  return score_skeletons(*model_, skeletons_.held_out, vectors_, device_);
}

std::vector<SkeletonScore> OwoTrainer::score_train() {
  return score_skeletons(*model_, skeletons_.train, vectors_, device_);
}

int64_t OwoTrainer::parameter_count() const {
  int64_t count = 0;
  for (const at::Tensor& p : model_->parameters()) count += p.numel();
  return count;
}

std::string OwoTrainer::describe_data(const std::vector<std::string>& data) const {
  std::string caches;
  for (const std::string& d : data) caches += (caches.empty() ? "" : ",") + d;
  int min_joints = 1 << 30, max_joints = 0;
  for (const PretrainSkeleton& s : skeletons_.train) {
    min_joints = std::min(min_joints, s.skeleton.joint_count());
    max_joints = std::max(max_joints, s.skeleton.joint_count());
  }
  std::vector<std::pair<std::string, int>> groups;
  for (const PretrainSkeleton& s : skeletons_.held_out) {
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == s.group; });
    if (it == groups.end()) {
      groups.emplace_back(s.group, 1);
    } else {
      ++it->second;
    }
  }
  std::string held;
  for (const auto& [group, count] : groups) held += (held.empty() ? "" : ", ") + group + " " + std::to_string(count);
  return "cache " + caches + ": " + std::to_string(skeletons_.train.size()) + " training skeletons (" +
         std::to_string(min_joints) + "-" + std::to_string(max_joints) + " joints, augmented), " +
         std::to_string(skeletons_.held_out.size()) + " held out" + (held.empty() ? "" : " (" + held + ")");
}

void OwoTrainer::save(const std::string& dir, int64_t step, const std::vector<std::string>& data) {
  json record = {{"format", kOwoTrainingFormat},
                 {"version", kOwoTrainingVersion},
                 {"step", step},
                 {"config", config_to_json(config_)},
                 {"data", data},
                 {"train_skeletons", json::array()},
                 {"held_out_skeletons", json::array()},
                 {"optimizer", kOptimizerFile}};
  for (const PretrainSkeleton& s : skeletons_.train) record["train_skeletons"].push_back(s.hash);
  for (const PretrainSkeleton& s : skeletons_.held_out) record["held_out_skeletons"].push_back(s.hash);
  const std::string description = describe_data(data);
  write_checkpoint_directory(dir, "an OwO training checkpoint", [&](const std::string& temp) {
    save_owo_checkpoint(temp, *model_, OwoCheckpointInfo{step, description});
    write_file_atomic((fs::path(temp) / kRecordFile).string(), record.dump(2) + "\n");
    try {
      torch::save(*optimizer_, (fs::path(temp) / kOptimizerFile).string());
    } catch (const c10::Error& e) {
      throw std::runtime_error(dir + ": cannot write the optimizer state: " + first_line(e.what()));
    }
  });
}

int64_t OwoTrainer::resume(const std::string& dir) {
  const std::string record_path = (fs::path(dir) / kRecordFile).string();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, 0, "no such checkpoint directory to resume from");
  const std::optional<OwoTrainingRecord> record = read_owo_training_record(dir);
  if (!record) {
    throw InputError(record_path, 0,
                     "missing: not a checkpoint written by `nec train owo`, nothing to resume; train into a new --out");
  }
  const std::vector<FieldDifference> changed = differences(record->config, config_);
  if (!changed.empty()) {
    std::string what;
    for (const FieldDifference& d : changed) {
      what += (what.empty() ? "" : ", ") + std::string("'") + d.field + "' (checkpoint " + d.then + ", now " + d.now + ")";
    }
    throw InputError(record_path, 0,
                     "cannot resume: the config differs in " + what +
                         "; resume with the config it was trained with (only steps and the log, validation and "
                         "checkpoint cadence may change), or train into a new --out");
  }
  std::set<std::string> then(record->train_skeletons.begin(), record->train_skeletons.end()), now;
  for (const PretrainSkeleton& s : skeletons_.train) now.insert(s.hash);
  if (then != now) {
    int added = 0, removed = 0;
    for (const std::string& h : now) added += then.count(h) ? 0 : 1;
    for (const std::string& h : then) removed += now.count(h) ? 0 : 1;
    throw InputError(record_path, 0,
                     "cannot resume: the training skeletons differ from the checkpoint's (" + std::to_string(added) +
                         " new, " + std::to_string(removed) + " missing); resume with the same --data, or train into "
                         "a new --out");
  }

  LoadedOwoCheckpoint loaded = load_owo_checkpoint(dir);
  if (loaded.info.training_step != record->step) {
    throw InputError(record_path, 0,
                     "step " + std::to_string(record->step) + " but config.json says " +
                         std::to_string(loaded.info.training_step) + "; the checkpoint is damaged");
  }
  {
    torch::NoGradGuard no_grad;
    auto source = loaded.model->named_parameters();
    for (auto& item : model_->named_parameters()) item.value().copy_(source[item.key()]);
    auto buffers = loaded.model->named_buffers();
    for (auto& item : model_->named_buffers()) item.value().copy_(buffers[item.key()]);
  }
  const std::string optimizer_path = (fs::path(dir) / kOptimizerFile).string();
  if (!fs::is_regular_file(optimizer_path, ec)) {
    throw InputError(optimizer_path, 0, "missing; the checkpoint is incomplete, cannot resume");
  }
  try {
    torch::load(*optimizer_, optimizer_path, device_);
  } catch (const c10::Error& e) {
    throw InputError(optimizer_path, 0, "cannot read the optimizer state: " + first_line(e.what()));
  }
  return record->step;
}

}  // namespace nec::owo

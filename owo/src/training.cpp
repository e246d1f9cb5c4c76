// OwO pretraining runs: config file, learning-rate schedule, batches, training checkpoints.
#include "nec/owo/training.h"

#include "nec/corpus/batch.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/checkpoint.h"
#include "nec/owo/graph.h"
#include "nec/owo/joint_names.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"
#include "nec/train/training_state.h"

#include <c10/util/Exception.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <stdexcept>

namespace nec::owo {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using train::JsonFields;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument(message);
}

OwoTrainingConfig config_from_json(const json& root, const std::string& file) {
  return train::read_valid_config<OwoTrainingConfig>(root, {file, "`nec train owo --help` lists every field", "", false});
}

json config_to_json(const OwoTrainingConfig& c) { return train::write_config(c); }

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

void visit_fields(train::ConfigVisitor& v, OwoDataConfig& c) {
  v.field("held_out", c.held_out, "skeletons held out of training, by label pattern");
  v.field("cache_held_out", c.cache_held_out, "also hold out what the caches hold out");
  v.field("poses_per_skeleton", c.poses_per_skeleton, "frames kept per skeleton for rest-pose augmentation");
  v.field("size_buckets", c.size_buckets, "a batch takes skeletons of one of this many joint-count ranges; 1 = any mix");
  v.object("augment", c.augment, "rig augmentation of the training skeletons");
}

void visit_fields(train::ConfigVisitor& v, OwoTrainingConfig& c) {
  v.object("encoder", c.encoder, "the OwO graph encoder (saved with the model)");
  v.object("pretrain", c.pretrain, "the self-supervised losses (saved with the model)");
  v.object("optimizer", c.optimizer, "AdamW, warm-up then cosine decay");
  v.object("data", c.data, "which skeletons train, and how they are augmented");
  v.field("names", c.names, "feed joint-name word vectors (encoder.name_dim = their width)");
  v.field("batch_size", c.batch_size, "skeletons per step at most");
  v.field("batch_joint_pairs", c.batch_joint_pairs, "and at most this many B x Jmax^2 per step; 0 = no limit");
  train::visit_cadence_fields(v, c.steps, c.log_every, c.validate_every, c.checkpoint_every);
  v.field("seed", c.seed, "initial weights, batches, augmentation and sampled pairs");
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
  try {
    optimizer.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("optimizer.") + e.what());
  }
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

OwoTrainingConfig read_owo_training_config(const std::string& path) {
  return parse_owo_training_config(read_file(path, size_t{1} << 24), path);
}

std::string owo_training_config_json(const OwoTrainingConfig& config) { return config_to_json(config).dump(2) + "\n"; }

std::vector<std::string> differing_fields(const OwoTrainingConfig& a, const OwoTrainingConfig& b) {
  return train::differing_fields(config_to_json(a), config_to_json(b), train::fields_that_may_change<OwoTrainingConfig>());
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

SkeletonSet split_as_trained(SkeletonSet set, const std::vector<std::string>& trained_hashes) {
  const std::set<std::string> trained(trained_hashes.begin(), trained_hashes.end());
  SkeletonSet out;
  out.unmatched_patterns = std::move(set.unmatched_patterns);
  for (PretrainSkeleton& s : set.held_out) {
    if (trained.count(s.hash)) {
      s.group = "train";
      out.train.push_back(std::move(s));
    } else {
      out.held_out.push_back(std::move(s));
    }
  }
  for (PretrainSkeleton& s : set.train) {
    if (trained.count(s.hash)) {
      out.train.push_back(std::move(s));
    } else {
      s.group = "not in its training set";
      out.held_out.push_back(std::move(s));
    }
  }
  return out;
}

// The OwO view of a training state read from `path`.
OwoTrainingRecord record_of(const train::TrainingState& state, const std::string& path) {
  const JsonFields fields(path, "the training state is damaged; train again into a new --out");
  OwoTrainingRecord record;
  record.step = state.step;
  record.config = config_from_json(state.config, path);
  record.schedule = state.schedule;
  record.data = string_list(fields, state.data, "caches");
  record.train_skeletons = string_list(fields, state.data, "train_skeletons");
  record.held_out_skeletons = string_list(fields, state.data, "held_out_skeletons");
  return record;
}

std::optional<OwoTrainingRecord> read_owo_training_record(const std::string& dir) {
  const std::optional<train::TrainingState> state = train::read_training_state(dir, "owo");
  if (!state) return std::nullopt;
  return record_of(*state, (fs::path(dir) / train::kTrainingStateFile).string());
}

OwoTrainer::OwoTrainer(const OwoTrainingConfig& config, SkeletonSet skeletons, const text::WordVectors* vectors,
                       const c10::Device& device, const train::Communicator* ranks)
    : config_(config),
      skeletons_(std::move(skeletons)),
      vectors_(config.names ? vectors : nullptr),
      device_(device),
      ranks_(ranks),
      schedule_(config.optimizer, config.steps) {
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
  optimizer_ = train::make_adamw(model_->parameters(), config_.optimizer);

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
  const uint64_t stream = mix64(config_.seed ^ mix64(static_cast<uint64_t>(step)));
  SplitMix64 rng(stream);

  // A bucket with probability proportional to its size, then skeletons uniformly within it.
  const size_t anchor = rng.below(skeletons_.train.size());
  size_t bucket = 0;
  for (size_t seen = 0; bucket < buckets_.size(); ++bucket) {
    seen += buckets_[bucket].size();
    if (anchor < seen) break;
  }
  const std::vector<size_t>& members = buckets_[std::min(bucket, buckets_.size() - 1)];
  // Up to batch_size skeletons, fewer when B * Jmax^2 would pass batch_joint_pairs (at least one).
  // Every rank draws the whole batch alike and keeps its share.
  std::vector<AugmentedSkeleton> rigs;
  int64_t largest = 0;
  for (int64_t b = 0; b < config_.batch_size; ++b) {
    const PretrainSkeleton& source = skeletons_.train[members[rng.below(members.size())]];
    AugmentedSkeleton rig = augment_skeleton(source, config_.data.augment, rng);
    const int64_t joints = std::max<int64_t>(largest, rig.skeleton.joint_count());
    if (b > 0 && config_.batch_joint_pairs > 0 && (b + 1) * joints * joints > config_.batch_joint_pairs) break;
    largest = joints;
    rigs.push_back(std::move(rig));
  }
  const int rank = ranks_ ? ranks_->rank() : 0, world = ranks_ ? ranks_->world_size() : 1;
  const BatchShare share = share_of(static_cast<int64_t>(rigs.size()), rank, world);
  const double weight = static_cast<double>(share.count) / static_cast<double>(rigs.size());

  optimizer_->zero_grad();
  PretrainLosses losses;
  if (share.count > 0) {
    std::vector<SkeletonGraph> graphs;
    for (int64_t i = share.begin; i < share.begin + share.count; ++i) {
      graphs.push_back(make_skeleton_graph(rigs[i].skeleton, names_of(rigs[i].canonical_names), config_.encoder.graph));
    }
    const GraphBatch batch = collate(graphs, config_.encoder.name_dim).to(device_);
    torch::manual_seed(mix64(stream) >> 1);  // the sampled joint pairs
    losses = model_->backward(batch, weight);
  }
  const train::OptimizerStep taken =
      train::optimizer_step(*optimizer_, model_->parameters(), config_.optimizer.grad_clip, schedule_.at(step), ranks_);
  losses.grad_norm = taken.grad_norm;
  if (ranks_ != nullptr) losses = summed_over_ranks(losses, weight);
  return losses;
}

PretrainLosses OwoTrainer::summed_over_ranks(const PretrainLosses& local, double weight) const {
  // The ranks' terms weighted by their shares: the terms of the whole batch. A
  // term counts where it ran (a rank without items ran none).
  PretrainLosses out = local;
  std::optional<double>* terms[] = {&out.offset, &out.pair_offset, &out.lca, &out.name, &out.lca_accuracy};
  constexpr int64_t kTerms = 1 + static_cast<int64_t>(std::size(terms));
  at::Tensor values = torch::zeros({2, kTerms}, torch::kDouble);  // (value x weight, ran)
  values[0][0] = out.total * weight;
  values[1][0] = 1.0;
  for (int64_t i = 1; i < kTerms; ++i) {
    if (!terms[i - 1]->has_value()) continue;
    values[0][i] = **terms[i - 1] * weight;
    values[1][i] = 1.0;
  }
  std::vector<at::Tensor> tensors{values};
  ranks_->sum(tensors);
  out.total = tensors[0][0][0].item<double>();
  for (int64_t i = 1; i < kTerms; ++i) {
    *terms[i - 1] = tensors[0][1][i].item<double>() > 0 ? std::optional<double>(tensors[0][0][i].item<double>())
                                                        : std::nullopt;
  }
  return out;
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

train::TrainingSchedule OwoTrainer::loop_schedule() const {
  return {config_.steps, config_.log_every, skeletons_.held_out.empty() ? 0 : config_.validate_every,
          config_.checkpoint_every};
}

train::TrainingHooks OwoTrainer::hooks(const std::string& out_dir, const std::vector<std::string>& data) {
  train::TrainingHooks hooks;
  hooks.step = [this](int64_t step) {
    const PretrainLosses l = this->step(step);
    train::LossTerms terms{{"total", l.total}};
    if (l.offset) terms.emplace_back("offset", *l.offset);
    if (l.pair_offset) terms.emplace_back("pair", *l.pair_offset);
    if (l.lca) terms.emplace_back("lca", *l.lca);
    if (l.name) terms.emplace_back("name", *l.name);
    if (l.lca_accuracy) terms.emplace_back("lca_acc", *l.lca_accuracy);
    if (l.grad_norm) terms.emplace_back("grad", *l.grad_norm);
    return terms;
  };
  hooks.validate = [this](int64_t) {
    const ScoreSummary held_out = summarize(score_held_out());
    return train::LossTerms{{"held_out_lca_acc", held_out.lca_accuracy},
                            {"offset_pct", held_out.offset_percent},
                            {"rebuilt", held_out.rebuild_rate},
                            {"decoded", held_out.decode_rate}};
  };
  hooks.checkpoint = [this, out_dir, data](int64_t step) { save(out_dir, step, data); };
  return hooks;
}

void OwoTrainer::save(const std::string& dir, int64_t step, const std::vector<std::string>& data) {
  train::TrainingState state;
  state.model = "owo";
  state.step = step;
  state.config = config_to_json(config_);
  state.schedule = schedule_.to_json();
  state.data = {{"caches", data}, {"train_skeletons", json::array()}, {"held_out_skeletons", json::array()}};
  for (const PretrainSkeleton& s : skeletons_.train) state.data["train_skeletons"].push_back(s.hash);
  for (const PretrainSkeleton& s : skeletons_.held_out) state.data["held_out_skeletons"].push_back(s.hash);
  const std::string description = describe_data(data);
  train::write_checkpoint_directory(dir, "an OwO training checkpoint", [&](const std::string& temp) {
    save_owo_checkpoint(temp, *model_, OwoCheckpointInfo{step, description});
    train::write_training_state(temp, state, *optimizer_);
  });
}

int64_t OwoTrainer::resume(const std::string& dir) {
  const std::string record_path = (fs::path(dir) / train::kTrainingStateFile).string();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, 0, "no such checkpoint directory to resume from");
  LoadedOwoCheckpoint loaded = load_owo_checkpoint(dir);
  const train::TrainingState state = train::resumable_state(dir, "owo", loaded.info.training_step);
  train::check_resumable(state, config_to_json(config_), train::fields_that_may_change<OwoTrainingConfig>(), record_path);
  const OwoTrainingRecord record = record_of(state, record_path);
  std::set<std::string> then(record.train_skeletons.begin(), record.train_skeletons.end()), now;
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

  train::copy_module_tensors(*loaded.model, *model_);
  train::load_optimizer_state(dir, *optimizer_, device_);
  schedule_ = train::LearningRateSchedule::resumed(config_.optimizer, record.schedule, record.step, config_.steps,
                                                   record_path);
  return record.step;
}

}  // namespace nec::owo

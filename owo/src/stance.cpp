// The stance network: model, checkpoint, examples from caches, scores and training.
#include "nec/owo/stance.h"

#include "nec/owo/graph.h"
#include "nec/owo/joint_names.h"
#include "nec/owo/skeleton_set.h"
#include "nec/corpus/rest_pose.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "nec/train/optimizer.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/random.h"
#include "nec/motion/rotations.h"
#include "nec/motion/statistics.h"

#include <fmt/format.h>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>

namespace nec::owo {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kArchitecture = "StanceNet";
constexpr const char* kConfigFile = "config.json";
constexpr const char* kTensorFile = "tensors.pt";
constexpr const char* kTrainHint = "run `nec train stance` to make one";

// A rig in one pose, as take_stance hands it to the network: the pose made the rest by preprocessing (the mean
// pose of one frame is that frame), facing +Z by its rule, +Y up as in the cache.
PreparedClip prepare_pose(const Skeleton& skeleton, const Motion& one_frame) {
  PreprocessOptions options;
  options.target_fps = 0.0;
  options.up = UpAxis::Y;
  options.min_frames = 1;
  PreparedClip prepared = preprocess(Clip{skeleton, one_frame, {}, ""}, "stance example", options);
  if (!prepared.report.accepted()) throw std::runtime_error("stance example rejected: " + prepared.report.rejection);
  return prepared;
}

// One frame whose global rotations are `globals` (J) on `skeleton`.
Motion pose_from_globals(const Skeleton& skeleton, const std::vector<Quat>& globals, double fps) {
  Motion motion = Motion::rest(skeleton, 1, fps);
  for (int j = 0; j < skeleton.joint_count(); ++j) {
    const int p = skeleton.parents[j];
    motion.rotation(0, j) = p < 0 ? globals[j] : (globals[p].conjugate() * globals[j]).normalized();
  }
  return motion;
}

Quat random_turn(SplitMix64& rng, double max_degrees) {
  Vec3 axis(rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0));
  if (axis.norm() < 1e-6) axis = Vec3::UnitX();
  return Quat(Eigen::AngleAxisd(rng.uniform(0.0, max_degrees) / kDegreesPerRadian, axis.normalized()));
}

at::Tensor vec3_rows(const std::vector<Vec3>& rows) {
  at::Tensor out = torch::zeros({static_cast<int64_t>(rows.size()), 3}, torch::kFloat32);
  auto a = out.accessor<float, 2>();
  for (size_t j = 0; j < rows.size(); ++j) {
    for (int k = 0; k < 3; ++k) a[static_cast<int64_t>(j)][k] = static_cast<float>(rows[j][k]);
  }
  return out;
}

SkeletonGraph graph_of(const Skeleton& bind, const std::vector<std::string>& names, const OwoConfig& config,
                       const text::WordVectors* vectors) {
  const at::Tensor embedded = config.name_dim > 0 ? name_embeddings(*vectors, names) : at::Tensor();
  return make_skeleton_graph(bind, embedded, config.graph);
}

// The network's stance directions (J) for one rig; the caller holds inference or no-grad mode.
std::vector<Vec3> read_directions(StanceNetImpl& net, const Skeleton& pose, const std::vector<std::string>& names,
                                  const text::WordVectors* vectors) {
  const OwoConfig& config = net.encoder->config();
  const SkeletonGraph graph = graph_of(pose, names, config, vectors);
  const at::Tensor directions = net.forward(collate({graph}, config.name_dim))[0].to(torch::kFloat64).contiguous();
  const auto a = directions.accessor<double, 2>();
  std::vector<Vec3> out(pose.joint_count());
  for (int j = 0; j < pose.joint_count(); ++j) out[j] = Vec3(a[j][0], a[j][1], a[j][2]);
  return out;
}

// The value below which a share `q` of the total weight lies.
double weighted_percentile(const std::vector<double>& values, const std::vector<double>& weights, double q) {
  std::vector<size_t> order(values.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return values[a] < values[b]; });
  double total = 0.0;
  for (const double w : weights) total += w;
  double below = 0.0;
  for (const size_t i : order) {
    below += weights[i];
    if (below >= q * total) return values[i];
  }
  return values.empty() ? 0.0 : values[order.back()];
}

}  // namespace

OwoConfig stance_encoder_config(int64_t name_dim) {
  OwoConfig config;
  config.name_dim = name_dim;
  config.dim = 64;
  config.layers = 3;
  config.heads = 4;
  config.edge_dim = 16;
  return config;
}

StanceNetImpl::StanceNetImpl(const OwoConfig& config) {
  config.validate();
  encoder = register_module("encoder", OwoEncoder(config));
  head_ = register_module("head", make_mlp(config.dim, config.dim, 3));
  // The head starts at zero: an untrained network keeps the bind pose, and training learns what to change.
  torch::NoGradGuard no_grad;
  for (at::Tensor& p : head_[2]->parameters()) p.zero_();
}

at::Tensor StanceNetImpl::forward(const GraphBatch& batch) {
  // Each bone's stance direction is its bind direction plus a correction: most bones of a bind pose already
  // point where the stance has them (spine, head, shins), and the network only has to move the others.
  const at::Tensor bind = batch.rest_offsets / batch.rest_offsets.norm(2, -1, true).clamp_min(1e-9);
  const at::Tensor raw = bind + head_->forward(encoder->forward(batch).joints);
  return raw / raw.norm(2, -1, true).clamp_min(1e-6);
}

void save_stance_checkpoint(const std::string& dir, StanceNetImpl& net, const StanceCheckpointInfo& info) {
  train::write_checkpoint_directory(dir, "a stance checkpoint", [&](const std::string& temp) {
    const json config = {{"format", kStanceCheckpointFormat},
                         {"version", kStanceCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"encoder", train::write_config(net.encoder->config())},
                         {"training_step", info.training_step},
                         {"passes", info.passes},
                         {"data", info.data},
                         {"validation", info.validation},
                         {"tensors", kTensorFile}};
    write_file_atomic((fs::path(temp) / kConfigFile).string(), config.dump(2) + "\n");
    train::save_module_tensors(net, (fs::path(temp) / kTensorFile).string());
  });
}

LoadedStance load_stance_checkpoint(const std::string& dir) {
  const train::CheckpointConfig config = train::read_checkpoint_config(
      dir, kStanceCheckpointFormat, kStanceCheckpointVersion, "a stance checkpoint", kTrainHint);
  const train::JsonFields reader = config.fields();
  const json& root = config.root;
  std::string architecture;
  reader.read(root, "architecture", "", architecture);
  if (architecture != kArchitecture) reader.fail("architecture '" + architecture + "' is not " + kArchitecture);
  const train::ReadOptions fields{config.path, reader.hint(), "", true};
  const OwoConfig encoder_config = train::read_config_object<OwoConfig>(root, "encoder", fields);
  LoadedStance loaded;
  reader.read(root, "training_step", "", loaded.info.training_step);
  if (root.contains("passes")) reader.read(root, "passes", "", loaded.info.passes);
  if (loaded.info.passes < 1) reader.fail("passes must be >= 1");
  reader.read(root, "data", "", loaded.info.data);
  if (root.contains("validation")) loaded.info.validation = root.at("validation");
  const std::string tensor_file = reader.entry(root, "tensors");
  try {
    encoder_config.validate();
    loaded.net = StanceNet(encoder_config);
  } catch (const std::invalid_argument& error) {
    reader.fail(std::string(error.what()) + "; the checkpoint is damaged, " + kTrainHint);
  }
  train::load_module_tensors(*loaded.net, (fs::path(dir) / tensor_file).string(), kTrainHint);
  loaded.net->eval();
  return loaded;
}

NetworkStance::NetworkStance(StanceNet net, StanceCheckpointInfo info, std::optional<text::WordVectors> vectors)
    : net_(std::move(net)), info_(std::move(info)), vectors_(std::move(vectors)) {}

NetworkStance NetworkStance::open(const std::string& dir, const std::string& glove) {
  LoadedStance loaded = load_stance_checkpoint(dir);
  const int64_t name_dim = loaded.net->encoder->config().name_dim;
  std::optional<text::WordVectors> vectors;
  if (name_dim > 0) vectors.emplace(text::WordVectors::load_checked(glove, name_dim));
  return NetworkStance(std::move(loaded.net), std::move(loaded.info), std::move(vectors));
}

void NetworkStance::set_passes(int64_t passes) {
  if (passes < 1) throw std::invalid_argument("a stance network reads the rig at least once (passes >= 1)");
  info_.passes = passes;
}

std::vector<Vec3> NetworkStance::bone_directions(const Skeleton& bind,
                                                 const std::vector<std::string>& canonical_names) const {
  c10::InferenceMode inference;
  const text::WordVectors* vectors = vectors_ ? &*vectors_ : nullptr;
  // Each pass reads the rig as the last one turned it: directions are world directions, so the last pass's are
  // the answer for `bind` too.
  std::vector<Vec3> out = read_directions(*net_, bind, canonical_names, vectors);
  Skeleton pose = bind;
  for (int64_t pass = 1; pass < info_.passes; ++pass) {
    pose = reexpress_skeleton(pose, stance_frames(pose, out));
    out = read_directions(*net_, pose, canonical_names, vectors);
  }
  return out;
}

std::vector<StanceExample> stance_examples(const DatasetCache& cache, const StanceExampleOptions& options) {
  const std::vector<PretrainSkeleton> rigs = skeletons_from_cache(cache, options.frames_per_rig, options.seed);
  std::vector<int> first_clip(rigs.size(), -1);
  for (int c = cache.clip_count() - 1; c >= 0; --c) first_clip[cache.clips[c].skeleton] = c;
  std::vector<StanceExample> out;
  for (size_t s = 0; s < rigs.size(); ++s) {
    const PretrainSkeleton& rig = rigs[s];
    if (first_clip[s] < 0) continue;
    const CacheClip& clip = cache.clips[first_clip[s]];
    bool held_out = rig.held_out_by_cache;
    for (const std::string& pattern : options.held_out) held_out = held_out || matches_hold_out(rig, pattern);
    const Skeleton& skeleton = rig.skeleton;
    const int joints = skeleton.joint_count();
    const PreparedClip file_truth = prepare_pose(skeleton, Motion::rest(skeleton, 1, cache.fps));
    SplitMix64 lengths_rng(mix64(options.seed ^ mix64(s + 1) ^ 0x5eedULL));
    auto add = [&](const std::string& pose, const Motion& one_frame) {
      if (held_out || options.length_jitter <= 0.0) {
        const PreparedClip bind = prepare_pose(skeleton, one_frame);
        out.push_back({rig.name, clip.dataset, pose, held_out, bind.clip.skeleton, file_truth.clip.skeleton,
                       bind.canonical_names});
        return;
      }
      // Other proportions, same tree and stance: every bone's length scaled on its own.
      Skeleton scaled = skeleton;
      for (Vec3& offset : scaled.offsets) {
        offset *= lengths_rng.uniform(1.0 - options.length_jitter, 1.0 + options.length_jitter);
      }
      const PreparedClip bind = prepare_pose(scaled, one_frame);
      const PreparedClip truth = prepare_pose(scaled, Motion::rest(scaled, 1, cache.fps));
      out.push_back({rig.name, clip.dataset, pose, held_out, bind.clip.skeleton, truth.clip.skeleton,
                     bind.canonical_names});
    };
    SplitMix64 rng(mix64(options.seed ^ mix64(s + 1)));
    auto turn_some = [&](Motion pose, double max_degrees) {
      for (int j = 0; j < joints; ++j) {
        if (rng.uniform() < options.turned_fraction) {
          pose.rotation(0, j) = (random_turn(rng, max_degrees) * pose.rotation(0, j)).normalized();
        }
      }
      return pose;
    };
    // The file's own rest pose (every local rotation zero): canonical global rotations R^-1 F_j^-1.
    std::optional<Motion> file_rest;
    if (static_cast<int>(clip.normalization.rest_frames.size()) == joints) {
      std::vector<Quat> globals(joints);
      for (int j = 0; j < joints; ++j) {
        globals[j] = (clip.normalization.rotation.conjugate() * clip.normalization.rest_frames[j].conjugate()).normalized();
      }
      file_rest = pose_from_globals(skeleton, globals, cache.fps);
      add("file rest", *file_rest);
    }
    for (int k = 0; k < rig.poses.frame_count; ++k) add("frame", rig.poses.slice(k, k + 1));
    for (int k = 0; k < options.turned_per_rig; ++k) {
      add("turned", turn_some(Motion::rest(skeleton, 1, cache.fps), options.turned_degrees));
    }
    // Bind poses near the file's (an A-pose, bent knees, a rigger's own): the stance should not depend on which.
    for (int k = 0; file_rest && k < options.rest_turned_per_rig; ++k) {
      add("rest turned", turn_some(*file_rest, options.rest_turned_degrees));
    }
  }
  return out;
}

json StanceScore::to_json() const {
  return {{"group", group},         {"examples", examples}, {"bones", bones},
          {"median_degrees", median}, {"mean_degrees", mean}, {"p90_degrees", p90},
          {"length_weighted_median_degrees", weighted_median}};
}

std::string by_dataset_and_pose(const StanceExample& example) { return example.dataset + " / " + example.pose; }

std::vector<StanceScore> score_stance(const StancePredictor& predictor, const std::vector<StanceExample>& examples,
                                      const std::function<std::string(const StanceExample&)>& group_of) {
  struct Pool {
    int64_t examples = 0;
    std::vector<double> errors, lengths;
  };
  std::vector<std::string> order;
  std::map<std::string, Pool> pooled;
  for (const StanceExample& example : examples) {
    const std::vector<Quat> frames =
        stance_frames(example.bind, predictor.bone_directions(example.bind, example.canonical_names));
    std::vector<double> lengths;
    const std::vector<double> errors =
        bone_direction_errors(reexpress_skeleton(example.bind, frames), example.stance, &lengths);
    for (const std::string& group : {group_of(example), std::string("all")}) {
      if (!pooled.count(group)) order.push_back(group);
      Pool& pool = pooled[group];
      ++pool.examples;
      pool.errors.insert(pool.errors.end(), errors.begin(), errors.end());
      pool.lengths.insert(pool.lengths.end(), lengths.begin(), lengths.end());
    }
  }
  std::vector<StanceScore> out;
  for (const std::string& group : order) {
    const std::vector<double>& errors = pooled[group].errors;
    StanceScore score;
    score.group = group;
    score.examples = pooled[group].examples;
    score.bones = static_cast<int64_t>(errors.size());
    score.median = upper_median(errors);
    score.weighted_median = weighted_percentile(errors, pooled[group].lengths, 0.5);
    score.p90 = lower_quantile(errors, 0.9);
    double sum = 0.0;
    for (const double e : errors) sum += e;
    score.mean = errors.empty() ? 0.0 : sum / static_cast<double>(errors.size());
    out.push_back(score);
  }
  return out;
}

StanceNet train_stance(const std::vector<StanceExample>& examples, const StanceTrainingOptions& options,
                       const text::WordVectors* vectors, const std::function<void(const std::string&)>& log) {
  if (options.name_dim > 0 && (vectors == nullptr || vectors->dim() != options.name_dim)) {
    throw std::invalid_argument("train_stance: joint names need word vectors of width " +
                                std::to_string(options.name_dim));
  }
  torch::manual_seed(options.seed);
  StanceNet net(stance_encoder_config(options.name_dim));
  const OwoConfig& config = net->encoder->config();
  // Every training example once as tensors: its graph, the true stance directions and which bones count.
  struct Prepared {
    SkeletonGraph graph;
    at::Tensor target;  // (J, 3)
    at::Tensor weight;  // (J) 1 where both poses have the bone
  };
  std::vector<Prepared> data;
  std::vector<const StanceExample*> trained;
  for (const StanceExample& example : examples) {
    if (example.held_out) continue;
    const std::vector<Vec3> bind = unit_bones(example.bind), truth = unit_bones(example.stance);
    at::Tensor weight = torch::zeros({example.bind.joint_count()}, torch::kFloat32);
    for (int j = 0; j < example.bind.joint_count(); ++j) {
      if (!bind[j].isZero() && !truth[j].isZero()) weight[j] = 1.0f;
    }
    data.push_back({graph_of(example.bind, example.canonical_names, config, vectors), vec3_rows(truth), weight});
    trained.push_back(&example);
  }
  if (data.empty()) throw std::invalid_argument("train_stance: no example is left for training");
  // Batches of similar joint counts (four buckets): the edge tensors grow with the largest rig.
  std::vector<size_t> by_size;
  const auto sort_by_size = [&] {
    by_size.resize(data.size());
    for (size_t i = 0; i < by_size.size(); ++i) by_size[i] = i;
    std::stable_sort(by_size.begin(), by_size.end(),
                     [&](size_t a, size_t b) { return data[a].graph.joint_count < data[b].graph.joint_count; });
  };
  sort_by_size();
  constexpr size_t kBuckets = 4;
  // With several passes the network reads rigs its own passes turned: from halfway, each training rig as the
  // network then turns it, pass after pass, against the same truth (so a rig already in its stance stays).
  const auto add_own_passes = [&] {
    torch::NoGradGuard no_grad;
    net->eval();
    const size_t originals = trained.size();
    for (size_t i = 0; i < originals; ++i) {
      Skeleton pose = trained[i]->bind;
      for (int64_t pass = 1; pass < options.passes; ++pass) {
        pose = reexpress_skeleton(pose, stance_frames(pose, read_directions(*net, pose, trained[i]->canonical_names,
                                                                            vectors)));
        data.push_back({graph_of(pose, trained[i]->canonical_names, config, vectors), data[i].target,
                        data[i].weight});
      }
    }
    net->train();
    sort_by_size();
  };

  train::OptimizerConfig optimizer_config;
  optimizer_config.learning_rate = options.learning_rate;
  optimizer_config.weight_decay = options.weight_decay;
  optimizer_config.warmup_steps = std::min<int64_t>(100, options.steps / 10);
  const train::LearningRateSchedule schedule(optimizer_config, options.steps);
  const std::vector<at::Tensor> parameters = net->parameters();
  const auto optimizer = train::make_adamw(parameters, optimizer_config);
  net->train();
  double loss_sum = 0.0;
  int64_t loss_count = 0;
  for (int64_t step = 1; step <= options.steps; ++step) {
    if (options.passes > 1 && step == options.steps / 2 + 1) add_own_passes();
    SplitMix64 rng(mix64(options.seed ^ mix64(static_cast<uint64_t>(step))));
    const size_t bucket = rng.below(kBuckets);
    const size_t begin = by_size.size() * bucket / kBuckets, end = std::max(begin + 1, by_size.size() * (bucket + 1) / kBuckets);
    std::vector<SkeletonGraph> graphs;
    std::vector<at::Tensor> targets, weights;
    const int64_t batch = std::min<int64_t>(options.batch_size, static_cast<int64_t>(end - begin));
    for (int64_t b = 0; b < batch; ++b) {
      const Prepared& p = data[by_size[begin + rng.below(end - begin)]];
      graphs.push_back(p.graph);
      targets.push_back(p.target);
      weights.push_back(p.weight);
    }
    const GraphBatch collated = collate(graphs, config.name_dim);
    const int64_t width = collated.max_joints();
    at::Tensor target = torch::zeros({batch, width, 3}), weight = torch::zeros({batch, width});
    for (int64_t b = 0; b < batch; ++b) {
      const int64_t joints = targets[b].size(0);
      target[b].narrow(0, 0, joints).copy_(targets[b]);
      weight[b].narrow(0, 0, joints).copy_(weights[b]);
    }
    optimizer->zero_grad();
    const at::Tensor cosine = (net->forward(collated) * target).sum(-1);
    const at::Tensor loss = ((1.0 - cosine) * weight).sum() / weight.sum().clamp_min(1.0);
    loss.backward();
    train::optimizer_step(*optimizer, parameters, 1.0, schedule.at(step));
    loss_sum += loss.item<double>();
    ++loss_count;
    if (log && (step % options.log_every == 0 || step == options.steps)) {
      // 1 - cos = 1 - cos(angle): the mean angle it stands for, roughly.
      const double mean_loss = loss_sum / static_cast<double>(loss_count);
      log(fmt::format("step {}/{}: loss {:.4f} (~{:.1f} degrees)", step, options.steps, mean_loss,
                      std::acos(std::clamp(1.0 - mean_loss, -1.0, 1.0)) * kDegreesPerRadian));
      loss_sum = 0.0;
      loss_count = 0;
    }
  }
  net->eval();
  return net;
}

}  // namespace nec::owo

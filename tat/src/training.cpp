// Tokenizer training: config file, steps, validation, checkpoints and resume.
#include "nec/tat/training.h"

#include "nec/corpus/augment.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/tat/batch_tensors.h"
#include "nec/tat/checkpoint.h"
#include "nec/tat/inference.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"
#include "nec/train/training_state.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <set>
#include <stdexcept>

namespace nec::tat {
namespace {

using nlohmann::json;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("TatTrainConfig: " + message);
}

// The loss terms of a step (ReconstructionLoss and the total), in the order they are logged.
constexpr const char* kLossTermNames[] = {"loss", "rotation", "root", "position", "velocity", "vertical", "commitment"};

// The loss terms of a step, in the order they are summed over the ranks.
std::vector<std::string> term_names(int64_t layers) {
  std::vector<std::string> names(std::begin(kLossTermNames), std::end(kLossTermNames));
  for (int64_t r = 0; r < layers; ++r) names.push_back("perplexity" + std::to_string(r));
  return names;
}

}  // namespace

void TatTrainConfig::validate() const {
  model.validate();
  loss.validate();
  try {
    optimizer.validate();
  } catch (const std::invalid_argument& e) {
    require(false, std::string("optimizer.") + e.what());
  }
  try {
    data.validate();
  } catch (const std::invalid_argument& e) {
    require(false, e.what());
  }
  require(steps >= 1 && batch_size >= 1, "steps and batch_size must be >= 1");
  require(data.window_frames >= model.downsampling() && data.window_frames % model.downsampling() == 0,
          "data.window_frames must be a positive multiple of the downsampling " + std::to_string(model.downsampling()) +
              ", got " + std::to_string(data.window_frames));
  require(max_joint_frames >= 0, "max_joint_frames must be >= 0");
  require(train::valid_cadence(log_every, validate_every, checkpoint_every), train::kCadenceRule);
  require(validation_batches >= 1, "validation_batches must be >= 1");
}

void visit_fields(train::ConfigVisitor& v, TatTrainConfig& c) {
  v.object("model", c.model, "the tokenizer");
  v.object("loss", c.loss, "weights of the reconstruction terms");
  v.object("optimizer", c.optimizer, "AdamW, warm-up then cosine decay");
  v.object("data", c.data, "how batches are cut from the cache");
  v.field("batch_size", c.batch_size, "clips per step over all processes");
  v.field("max_joint_frames", c.max_joint_frames,
          "most B x J x T entries per forward pass; bigger batches run in parts (same update); 0 = no limit");
  v.field("validation_batches", c.validation_batches, "batches of the val split per validation");
  train::visit_cadence_fields(v, c.steps, c.log_every, c.validate_every, c.checkpoint_every);
  v.field("seed", c.seed, "initial weights, batches and every step's random draws");
}

TatTrainConfig tat_train_config_from_json(const json& object, const std::string& file) {
  return train::read_valid_config<TatTrainConfig>(object, {file, "`nec train tat --help` lists every field", "", false});
}

TatTrainConfig read_tat_train_config(const std::string& path) {
  return tat_train_config_from_json(train::read_config_json(path), path);
}

struct TatTrainer::Inputs {
  BatchTensors batch;
  at::Tensor embeddings;  // (B, J, D) or undefined
};

TatTrainer::TatTrainer(const TatTrainConfig& config, const DatasetCache& cache, std::string data_name,
                       owo::OwoPretrainer owo, const text::WordVectors* vectors, const c10::Device& device,
                       const train::Communicator* ranks)
    : config_(config),
      cache_(cache),
      data_name_(std::move(data_name)),
      owo_(std::move(owo)),
      vectors_(vectors),
      device_(device),
      ranks_(ranks),
      schedule_(config.optimizer, config.steps) {
  config_.validate();
  torch::manual_seed(static_cast<uint64_t>(config_.seed));  // the initial weights and codebooks
  tokenizer_ = Tokenizer(config_.model);
  tokenizer_->to(device_);
  tokenizer_->train();
  tokenizer_->set_communicator(ranks_);
  owo_->to(device_);
  owo_->eval();
  for (auto& parameter : owo_->parameters()) parameter.set_requires_grad(false);
  if (config_.model.kind != TokenizerKind::ZeroPadRvq) {
    skeleton_embeddings_ =
        std::make_unique<RememberedSkeletonEmbeddings>(owo_->encoder, vectors_, cache_, train::kRememberedEncodingBytes);
  }
  optimizer_ = train::make_adamw(tokenizer_->parameters(), config_.optimizer);

  BatchOptions batches = train::training_batches(config_.data, config_.batch_size, config_.seed, ranks_);
  if (config_.model.kind == TokenizerKind::ZeroPadRvq) {
    // Subdivision adds joints beyond the fixed channel layout of the padding baseline.
    batches.augment_kinds = {AugmentKind::RestPose, AugmentKind::BoneLength, AugmentKind::JointRemoval};
  }
  BatchOptions validation = batches;
  validation.augment_probability = 0.0;
  validation.joint_buckets = 0;
  validation.shuffle = false;
  validation.drop_last = false;
  validation.shard_rank = 0;
  validation.shard_count = 1;
  if (ranks_ != nullptr && config_.batch_size < ranks_->world_size()) {
    throw std::invalid_argument("batch_size " + std::to_string(config_.batch_size) + " is smaller than the " +
                                std::to_string(ranks_->world_size()) + " ranks: each rank needs a share");
  }
  const int64_t train_clips = static_cast<int64_t>(cache.clips_in(Split::Train).size());
  if (train_clips < config_.batch_size) {
    throw InputError(data_name_, 0,
                     "the train split has " + std::to_string(train_clips) + " clips, fewer than one batch of " +
                         std::to_string(config_.batch_size));
  }
  train_ = std::make_unique<BatchLoader>(cache, Split::Train, batches);
  if (!cache.clips_in(Split::Val).empty()) validation_ = std::make_unique<BatchLoader>(cache, Split::Val, validation);
}

TatTrainer::~TatTrainer() = default;

int64_t TatTrainer::parameter_count() const {
  int64_t count = 0;
  for (const at::Tensor& p : tokenizer_->parameters()) count += p.numel();
  return count;
}

TatTrainer::Inputs TatTrainer::inputs(const Batch& batch) {
  Inputs in;
  in.batch = to_tensors(batch).to(device_);
  if (config_.model.kind != TokenizerKind::ZeroPadRvq) {
    in.embeddings = skeleton_embeddings_->embed(batch);
  }
  return in;
}

int64_t items_per_part(int64_t items, int64_t joint_frames_per_item, int64_t max_joint_frames) {
  if (max_joint_frames <= 0) return items;
  return std::clamp<int64_t>(max_joint_frames / std::max<int64_t>(1, joint_frames_per_item), 1, std::max<int64_t>(1, items));
}

LossTerms backward_in_parts(Tokenizer& tokenizer, const BatchTensors& batch, const at::Tensor& embeddings,
                            const LossWeights& weights, int64_t max_joint_frames, double batch_share) {
  const int64_t items = batch.features.size(0);
  const int64_t part_items =
      items_per_part(items, batch.features.size(1) * batch.features.size(2), max_joint_frames);
  LossTerms terms;
  at::Tensor perplexity;
  for (int64_t begin = 0; begin < items; begin += part_items) {
    const int64_t count = std::min(part_items, items - begin);
    const double share = batch_share * static_cast<double>(count) / static_cast<double>(items);
    const BatchTensors part = batch.items(begin, count);
    const TokenizerOutput out = tokenizer->forward(part.features, part.joint_mask, part.frame_mask,
                                                   embeddings.defined() ? embeddings.narrow(0, begin, count) : embeddings);
    const ReconstructionLoss loss = reconstruction_loss(out.reconstruction, part, out.commitment_loss, weights);
    (loss.total * share).backward();
    terms["loss"] += share * loss.total.item<double>();
    terms["rotation"] += share * loss.rotation;
    terms["root"] += share * loss.root;
    terms["position"] += share * loss.position;
    terms["velocity"] += share * loss.velocity;
    terms["vertical"] += share * loss.vertical;
    terms["commitment"] += share * loss.commitment;
    const at::Tensor part_perplexity = out.perplexity.detach().to(torch::kCPU, torch::kFloat64) * share;
    perplexity = perplexity.defined() ? perplexity + part_perplexity : part_perplexity;
  }
  for (int64_t r = 0; r < perplexity.numel(); ++r) terms["perplexity" + std::to_string(r)] = perplexity[r].item<double>();
  return terms;
}

LossTerms TatTrainer::step(int64_t step) { return step_on(train_->next(), step); }

LossTerms TatTrainer::step_on(const Batch& batch, int64_t step) {
  // The step's random draws (quantize dropout, dead-code reset) depend on the
  // seed and the step alone: a run is repeatable, and a resumed run takes the
  // steps of one that never stopped.
  torch::manual_seed(static_cast<uint64_t>(config_.seed) * 1000003u + static_cast<uint64_t>(step - 1));
  const double lr = schedule_.at(step);
  const double share = batch.global_size > 0 ? static_cast<double>(batch.size) / batch.global_size : 1.0;
  tokenizer_->train();
  optimizer_->zero_grad();
  LossTerms terms;
  if (batch.size > 0) {
    const Inputs in = inputs(batch);
    terms = backward_in_parts(tokenizer_, in.batch, in.embeddings, config_.loss.at_step(step),
                              config_.max_joint_frames, share);
  }
  const train::OptimizerStep taken = train::optimizer_step(*optimizer_, tokenizer_->parameters(), config_.optimizer.grad_clip,
                                                           lr, ranks_);
  tokenizer_->update_codebooks();
  if (ranks_ != nullptr) {
    // Every rank reports the whole batch's terms; each term is named by every rank (the same model).
    const std::vector<std::string> names = term_names(config_.model.quantizer.layers);
    at::Tensor values = torch::zeros({static_cast<int64_t>(names.size())}, torch::kDouble);
    for (size_t i = 0; i < names.size(); ++i) {
      const auto found = terms.find(names[i]);
      if (found != terms.end()) values[static_cast<int64_t>(i)] = found->second;
    }
    std::vector<at::Tensor> summed{values};
    ranks_->sum(summed);
    for (size_t i = 0; i < names.size(); ++i) terms[names[i]] = summed[0][static_cast<int64_t>(i)].item<double>();
  }
  terms["grad_norm"] = taken.grad_norm;
  terms["lr"] = lr;
  return terms;
}

std::optional<ReconstructionMetrics> TatTrainer::validate() {
  if (!validation_) return std::nullopt;
  ReconstructionMetrics metrics;
  const int count = std::min<int>(static_cast<int>(config_.validation_batches), validation_->batches_per_epoch());
  for (int i = 0; i < count; ++i) metrics.add(evaluate(validation_->batch(0, i)));
  return metrics;
}

train::TrainingSchedule TatTrainer::loop_schedule() const {
  return {config_.steps, config_.log_every, has_validation() ? config_.validate_every : 0, config_.checkpoint_every};
}

train::TrainingHooks TatTrainer::hooks(const std::string& out_dir) {
  train::TrainingHooks hooks;
  hooks.step = [this](int64_t step) {
    const LossTerms terms = this->step(step);
    train::LossTerms out;
    for (const char* key : kLossTermNames) {
      out.emplace_back(key, terms.at(key));
    }
    for (int64_t r = 0; r < config_.model.quantizer.layers; ++r) {
      const auto it = terms.find("perplexity" + std::to_string(r));
      if (it != terms.end()) out.emplace_back("ppl" + std::to_string(r), it->second);
    }
    out.emplace_back("lr", terms.at("lr"));
    return out;
  };
  hooks.validate = [this](int64_t) {
    const std::optional<ReconstructionMetrics> metrics = validate();
    return train::LossTerms{{"val_mpjpe", metrics->mpjpe()},
                            {"val_mpjpe_no_trans", metrics->mpjpe_no_translation()},
                            {"val_geodesic_deg", metrics->geodesic_degrees()},
                            {"val_turning_kept", metrics->pose_turn_kept()}};
  };
  hooks.checkpoint = [this, out_dir](int64_t step) { save(out_dir, step); };
  return hooks;
}

void TatTrainer::save(const std::string& dir, int64_t step) {
  TatCheckpointInfo info;
  info.window_frames = config_.data.window_frames;
  info.fps = cache_.fps;
  info.training_step = step;
  info.data = data_name_ + " (" + std::to_string(train_->clip_count()) + " train clips)";
  train::TrainingState state;
  state.model = "tat";
  state.step = step;
  state.config = train::write_config(config_);
  state.schedule = schedule_.to_json();
  state.data = train::batch_position(*train_);
  save_tat_checkpoint(dir, *tokenizer_, *owo_, info,
                      [&](const std::string& temp) { train::write_training_state(temp, state, *optimizer_); });
}

int64_t TatTrainer::resume(const std::string& dir) {
  const std::string state_path = (std::filesystem::path(dir) / train::kTrainingStateFile).string();
  LoadedTatCheckpoint loaded = load_tat_checkpoint(dir);
  const train::TrainingState state = train::resumable_state(dir, "tat", loaded.info.training_step);
  train::check_resumable(state, train::write_config(config_), train::fields_that_may_change<TatTrainConfig>(), state_path);
  train::copy_module_tensors(*loaded.tokenizer, *tokenizer_);
  train::load_optimizer_state(dir, *optimizer_, device_);
  schedule_ = train::LearningRateSchedule::resumed(config_.optimizer, state.schedule, state.step, config_.steps,
                                                   state_path);
  train::seek_batches(*train_, state.data, state_path);
  return state.step;
}

ReconstructionMetrics TatTrainer::evaluate(const Batch& batch) {
  const Inputs in = inputs(batch);
  tokenizer_->eval();
  ReconstructionMetrics metrics;
  {
    torch::NoGradGuard no_grad;
    const TokenizerOutput out =
        tokenizer_->forward(in.batch.features, in.batch.joint_mask, in.batch.frame_mask, in.embeddings);
    metrics.add(out.reconstruction, in.batch.features, in.batch.parents, in.batch.offsets, in.batch.joint_mask,
                in.batch.frame_mask);
  }
  tokenizer_->train();
  return metrics;
}

}  // namespace nec::tat

// Tokenizer training: config file, learning-rate schedule, steps and validation.
#include "nec/tat/training.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/checkpoint_io.h"
#include "nec/tat/batch_tensors.h"
#include "nec/tat/checkpoint.h"
#include "nec/tat/inference.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace nec::tat {
namespace {

using nlohmann::json;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("TatTrainConfig: " + message);
}

void reject_unknown(const json& object, const std::set<std::string>& known, const owo::JsonFields& fields,
                    const std::string& where) {
  for (const auto& item : object.items()) {
    if (!known.count(item.key())) fields.fail("unknown field '" + where + item.key() + "'");
  }
}

}  // namespace

void TatTrainConfig::validate() const {
  model.validate();
  loss.validate();
  require(learning_rate > 0 && final_learning_rate >= 0 && final_learning_rate <= learning_rate,
          "need learning_rate > 0 and 0 <= final_learning_rate <= learning_rate");
  require(warmup_steps >= 0 && weight_decay >= 0 && grad_clip >= 0,
          "warmup_steps, weight_decay and grad_clip must be >= 0");
  require(steps >= 1 && batch_size >= 1, "steps and batch_size must be >= 1");
  require(window_frames >= model.downsampling() && window_frames % model.downsampling() == 0,
          "window_frames must be a positive multiple of the downsampling " + std::to_string(model.downsampling()) +
              ", got " + std::to_string(window_frames));
  require(augment_probability >= 0 && augment_probability <= 1, "augment_probability must be in [0, 1]");
  require(joint_buckets >= 0 && max_joint_frames >= 0, "joint_buckets and max_joint_frames must be >= 0");
  require(log_every >= 1 && validate_every >= 1 && checkpoint_every >= 1 && validation_batches >= 1,
          "log_every, validate_every, checkpoint_every and validation_batches must be >= 1");
}

json to_json(const TatTrainConfig& c) {
  return {{"model", to_json(c.model)},
          {"loss",
           {{"rotation", c.loss.rotation},
            {"root", c.loss.root},
            {"position", c.loss.position},
            {"velocity", c.loss.velocity}}},
          {"learning_rate", c.learning_rate},
          {"final_learning_rate", c.final_learning_rate},
          {"warmup_steps", c.warmup_steps},
          {"weight_decay", c.weight_decay},
          {"grad_clip", c.grad_clip},
          {"steps", c.steps},
          {"batch_size", c.batch_size},
          {"window_frames", c.window_frames},
          {"augment_probability", c.augment_probability},
          {"joint_buckets", c.joint_buckets},
          {"max_joint_frames", c.max_joint_frames},
          {"log_every", c.log_every},
          {"validate_every", c.validate_every},
          {"validation_batches", c.validation_batches},
          {"checkpoint_every", c.checkpoint_every},
          {"seed", c.seed}};
}

TatTrainConfig tat_train_config_from_json(const json& object, const std::string& file) {
  const owo::JsonFields fields(file, "see configs/tat_cpu.json for every field and its default");
  if (!object.is_object()) fields.fail("a training config must be a JSON object");
  reject_unknown(object,
                 {"model", "loss", "learning_rate", "final_learning_rate", "warmup_steps", "weight_decay", "grad_clip",
                  "steps", "batch_size", "window_frames", "augment_probability", "joint_buckets", "max_joint_frames",
                  "log_every", "validate_every", "validation_batches", "checkpoint_every", "seed", "comment"},
                 fields, "");
  TatTrainConfig c;
  if (object.contains("model")) {
    const json& model = fields.object(object, "model", "");
    reject_unknown(model, {"kind", "joint_embedding_dim", "dim", "blocks", "attention_layers", "heads", "max_joints",
                           "quantizer"},
                   fields, "model.");
    if (model.contains("quantizer")) {
      reject_unknown(fields.object(model, "quantizer", "model."),
                     {"layers", "codebook_size", "code_dim", "ema_decay", "commitment_weight", "dead_code_threshold",
                      "quantize_dropout"},
                     fields, "model.quantizer.");
    }
    c.model = tat_config_from_json(model, file, "model.");
  }
  auto read = [&](const json& parent, const char* key, const std::string& where, auto& out) {
    if (parent.contains(key)) fields.read(parent, key, where, out);
  };
  if (object.contains("loss")) {
    const json& loss = fields.object(object, "loss", "");
    reject_unknown(loss, {"rotation", "root", "position", "velocity"}, fields, "loss.");
    read(loss, "rotation", "loss.", c.loss.rotation);
    read(loss, "root", "loss.", c.loss.root);
    read(loss, "position", "loss.", c.loss.position);
    read(loss, "velocity", "loss.", c.loss.velocity);
  }
  read(object, "learning_rate", "", c.learning_rate);
  read(object, "final_learning_rate", "", c.final_learning_rate);
  read(object, "warmup_steps", "", c.warmup_steps);
  read(object, "weight_decay", "", c.weight_decay);
  read(object, "grad_clip", "", c.grad_clip);
  read(object, "steps", "", c.steps);
  read(object, "batch_size", "", c.batch_size);
  read(object, "window_frames", "", c.window_frames);
  read(object, "augment_probability", "", c.augment_probability);
  read(object, "joint_buckets", "", c.joint_buckets);
  read(object, "max_joint_frames", "", c.max_joint_frames);
  read(object, "log_every", "", c.log_every);
  read(object, "validate_every", "", c.validate_every);
  read(object, "validation_batches", "", c.validation_batches);
  read(object, "checkpoint_every", "", c.checkpoint_every);
  read(object, "seed", "", c.seed);
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    fields.fail(e.what());
  }
  return c;
}

TatTrainConfig read_tat_train_config(const std::string& path) {
  json root;
  try {
    root = json::parse(read_file(path, size_t{1} << 24));
  } catch (const json::parse_error& error) {
    throw InputError(path, 0, std::string("not valid JSON: ") + error.what());
  }
  return tat_train_config_from_json(root, path);
}

double learning_rate_at(const TatTrainConfig& c, int64_t step) {
  if (step < c.warmup_steps) return c.learning_rate * static_cast<double>(step + 1) / static_cast<double>(c.warmup_steps);
  const double span = std::max<int64_t>(1, c.steps - c.warmup_steps);
  const double progress = std::min(1.0, static_cast<double>(step - c.warmup_steps) / span);
  return c.final_learning_rate + 0.5 * (c.learning_rate - c.final_learning_rate) * (1.0 + std::cos(M_PI * progress));
}

struct TatTrainer::Inputs {
  BatchTensors batch;
  at::Tensor embeddings;  // (B, J, D) or undefined
};

TatTrainer::TatTrainer(Tokenizer tokenizer, owo::OwoPretrainer owo, const TatTrainConfig& config,
                       const text::WordVectors* vectors, const c10::Device& device)
    : tokenizer_(std::move(tokenizer)), owo_(std::move(owo)), config_(config), vectors_(vectors), device_(device) {
  config_.validate();
  tokenizer_->to(device_);
  tokenizer_->train();
  owo_->to(device_);
  owo_->eval();
  for (auto& parameter : owo_->parameters()) parameter.set_requires_grad(false);
  optimizer_ = std::make_unique<torch::optim::AdamW>(
      tokenizer_->parameters(),
      torch::optim::AdamWOptions(config_.learning_rate).weight_decay(config_.weight_decay));
}

TatTrainer::Inputs TatTrainer::inputs(const Batch& batch) {
  Inputs in;
  in.batch = to_tensors(batch).to(device_);
  if (config_.model.kind != TokenizerKind::ZeroPadRvq) {
    in.embeddings = embed_skeletons(*owo_->encoder, batch.skeletons, batch.canonical_names, vectors_).clone();
  }
  return in;
}

int64_t items_per_part(int64_t items, int64_t joint_frames_per_item, int64_t max_joint_frames) {
  if (max_joint_frames <= 0) return items;
  return std::clamp<int64_t>(max_joint_frames / std::max<int64_t>(1, joint_frames_per_item), 1, std::max<int64_t>(1, items));
}

LossTerms backward_in_parts(Tokenizer& tokenizer, const BatchTensors& batch, const at::Tensor& embeddings,
                            const LossWeights& weights, int64_t max_joint_frames) {
  const int64_t items = batch.features.size(0);
  const int64_t part_items =
      items_per_part(items, batch.features.size(1) * batch.features.size(2), max_joint_frames);
  LossTerms terms;
  at::Tensor perplexity;
  for (int64_t begin = 0; begin < items; begin += part_items) {
    const int64_t count = std::min(part_items, items - begin);
    const double share = static_cast<double>(count) / static_cast<double>(items);
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
    terms["commitment"] += share * loss.commitment;
    const at::Tensor part_perplexity = out.perplexity.detach().to(torch::kCPU, torch::kFloat64) * share;
    perplexity = perplexity.defined() ? perplexity + part_perplexity : part_perplexity;
  }
  for (int64_t r = 0; r < perplexity.numel(); ++r) terms["perplexity" + std::to_string(r)] = perplexity[r].item<double>();
  return terms;
}

LossTerms TatTrainer::step(const Batch& batch, int64_t step_index) {
  // The step's random draws (quantize dropout, dead-code reset) depend on the
  // seed and the step alone: a run is repeatable, and a resumed run takes the
  // steps of one that never stopped.
  torch::manual_seed(static_cast<uint64_t>(config_.seed) * 1000003u + static_cast<uint64_t>(step_index));
  const double lr = learning_rate_at(config_, step_index);
  for (auto& group : optimizer_->param_groups()) static_cast<torch::optim::AdamWOptions&>(group.options()).lr(lr);
  const Inputs in = inputs(batch);
  tokenizer_->train();
  optimizer_->zero_grad();
  LossTerms terms = backward_in_parts(tokenizer_, in.batch, in.embeddings, config_.loss, config_.max_joint_frames);
  if (config_.grad_clip > 0) torch::nn::utils::clip_grad_norm_(tokenizer_->parameters(), config_.grad_clip);
  optimizer_->step();
  terms["lr"] = lr;
  return terms;
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

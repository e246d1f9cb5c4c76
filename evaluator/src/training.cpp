// Evaluator training: config file, contrastive steps, R-Precision validation,
// checkpoints with the best model kept, resume.
#include "nec/evaluator/training.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/random.h"
#include "nec/tat/batch_tensors.h"
#include "nec/tat/inference.h"
#include "nec/text/caption_text.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"
#include "nec/train/training_state.h"

#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <stdexcept>

namespace nec::evaluator {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Keeps the synonym draws apart from the step's other draws.
constexpr uint64_t kSynonymStream = 0x53594e4f4e594d53ULL;  // "SYNONYMS"

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("EvaluatorTrainConfig: " + message);
}

}  // namespace

void EvaluatorTrainConfig::validate() const {
  model.validate();
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
  require(captions.synonym_probability >= 0 && captions.synonym_probability <= 1,
          "captions.synonym_probability must be in [0, 1]");
  try {
    captions.synonyms.validate();
  } catch (const std::invalid_argument& e) {
    require(false, std::string("captions.synonyms.") + e.what());
  }
  require(captions.teacher_weight >= 0, "captions.teacher_weight must be >= 0");
  require(captions.teacher_temperature > 0, "captions.teacher_temperature must be > 0");
  require(captions.teacher_weight == 0 || model.text.backbone == text::kUseLiteBackbone,
          "captions.teacher_weight needs the text backbone \"use-lite\" (the teacher is its sentence encoder)");
  require(steps >= 1 && batch_size >= 2, "steps must be >= 1 and batch_size >= 2");
  require(data.window_frames <= model.motion.max_frames(),
          "data.window_frames must be at most model.motion.max_frames() = " + std::to_string(model.motion.max_frames()));
  require(train::valid_cadence(log_every, validate_every, checkpoint_every), train::kCadenceRule);
}

void visit_fields(train::ConfigVisitor& v, CaptionAugmentConfig& c) {
  v.added_field("synonym_probability", c.synonym_probability,
          "chance that a train caption word is replaced by one of its word-vector synonyms; 0 = off");
  v.object("synonyms", c.synonyms, "which word-vector neighbours count as synonyms");
  v.added_field("teacher_weight", c.teacher_weight,
                "weight of the sentence encoder's caption-to-caption similarities as a teacher of the head; 0 = off");
  v.added_field("teacher_temperature", c.teacher_temperature, "temperature of those similarities");
}

void visit_fields(train::ConfigVisitor& v, EvaluatorTrainConfig& c) {
  v.object("model", c.model, "the motion and text encoders");
  v.object("optimizer", c.optimizer, "AdamW, warm-up then cosine decay");
  v.object("data", c.data, "how batches are cut from the cache");
  v.object("captions", c.captions, "caption augmentation: synonyms from the word vectors");
  v.field("batch_size", c.batch_size, "(clip, caption) pairs per step over all processes");
  train::visit_cadence_fields(v, c.steps, c.log_every, c.validate_every, c.checkpoint_every);
  v.field("seed", c.seed, "initial weights, batches and every step's random draws");
}

EvaluatorTrainConfig read_evaluator_train_config(const std::string& path) {
  return train::read_config_file<EvaluatorTrainConfig>(path, "`nec train evaluator --help` lists every field");
}

at::Tensor contrastive_loss(const at::Tensor& motion, const at::Tensor& text, const at::Tensor& scale,
                            const at::Tensor& same) {
  const at::Tensor logits = scale * motion.matmul(text.t());  // (B, B): motion i against text j
  const at::Tensor targets = same.to(logits.scalar_type());
  const at::Tensor rows = targets / targets.sum(1, true);
  const at::Tensor columns = targets / targets.sum(0, true);
  const at::Tensor motion_to_text = -(rows * torch::log_softmax(logits, 1)).sum(1).mean();
  const at::Tensor text_to_motion = -(columns * torch::log_softmax(logits, 0)).sum(0).mean();
  return 0.5 * (motion_to_text + text_to_motion);
}

at::Tensor caption_teacher_loss(const at::Tensor& text, const at::Tensor& teacher, double temperature) {
  const int64_t batch = text.size(0);
  const at::Tensor others = ~torch::eye(batch, torch::TensorOptions().dtype(torch::kBool).device(text.device()));
  const auto row_distribution = [&](const at::Tensor& rows) {
    const at::Tensor similarities = rows.matmul(rows.t()) / temperature;
    return torch::log_softmax(similarities.masked_fill(~others, -1e9), 1);
  };
  const at::Tensor target = row_distribution(teacher.detach().to(text.scalar_type()));
  const at::Tensor head = row_distribution(text);
  return (target.exp() * (target - head)).masked_fill(~others, 0).sum(1).mean();
}

at::Tensor contrastive_batch_loss(EvaluatorImpl& model, const ContrastiveBatch& batch, double teacher_weight,
                                  double teacher_temperature) {
  const at::Tensor motion =
      model.embed_motion(batch.features, batch.joint_mask, batch.frame_mask, batch.joint_embeddings);
  const at::Tensor text = model.embed_text(batch.captions);
  const at::Tensor loss = contrastive_loss(motion, text, model.logit_scale(), batch.same);
  if (teacher_weight <= 0) return loss;
  return loss + teacher_weight * caption_teacher_loss(text, batch.captions.encoder_sentence, teacher_temperature);
}

std::vector<int> captioned_clips(const DatasetCache& cache, Split split) {
  std::vector<int> out;
  for (const int clip : cache.clips_in(split)) {
    if (!cache.clips[static_cast<size_t>(clip)].captions.empty()) out.push_back(clip);
  }
  return out;
}

EvaluatorTrainer::EvaluatorTrainer(const EvaluatorTrainConfig& config, const DatasetCache& cache, std::string data_name,
                                   owo::OwoPretrainer owo, text::CaptionReader captions,
                                   const text::WordVectors* vectors, const c10::Device& device,
                                   const train::Communicator* ranks)
    : config_(config),
      cache_(cache),
      data_name_(std::move(data_name)),
      owo_(std::move(owo)),
      captions_(std::move(captions)),
      vectors_(vectors),
      device_(device),
      ranks_(ranks),
      schedule_(config.optimizer, config.steps) {
  config_.validate();
  torch::manual_seed(config_.seed);
  model_ = Evaluator(config_.model);
  if (vectors_ != nullptr && config_.model.text.word_dim > 0) {
    model_->text->init_piece_embeddings(*captions_.pieces(), *vectors_);
  }
  model_->to(device_);
  model_->train();
  owo_->to(device_);
  owo_->eval();
  for (auto& parameter : owo_->parameters()) parameter.set_requires_grad(false);
  optimizer_ = train::make_adamw(model_->parameters(), config_.optimizer);

  const std::vector<int> train_clips = captioned_clips(cache, Split::Train);
  captions_.check_corpus(cache, data_name_);
  captions_.remember_corpus_encodings(cache, train::kRememberedEncodingBytes);
  skeleton_embeddings_ =
      std::make_unique<tat::RememberedSkeletonEmbeddings>(owo_->encoder, vectors_, cache, train::kRememberedEncodingBytes);
  if (static_cast<int64_t>(train_clips.size()) < config_.batch_size) {
    throw InputError(data_name_, 0,
                     "the train split has " + std::to_string(train_clips.size()) +
                         " clips with captions, fewer than one batch of " + std::to_string(config_.batch_size));
  }
  if (ranks_ != nullptr && config_.batch_size < 2 * ranks_->world_size()) {
    throw std::invalid_argument("batch_size " + std::to_string(config_.batch_size) + " gives fewer than 2 items to each of the " +
                                std::to_string(ranks_->world_size()) + " ranks: a contrastive share needs 2");
  }
  train_ = std::make_unique<BatchLoader>(cache, train_clips,
                                         train::training_batches(config_.data, config_.batch_size, config_.seed, ranks_));
  if (config_.captions.synonym_probability > 0) {
    if (vectors_ == nullptr) {
      throw std::invalid_argument("captions.synonym_probability " + std::to_string(config_.captions.synonym_probability) +
                                  " needs word vectors");
    }
    std::vector<std::string> words;
    for (const int clip : train_clips) {
      for (const std::string& caption : cache.clips[static_cast<size_t>(clip)].captions) {
        for (std::string& word : text::caption_words(text::normalize_caption(caption))) words.push_back(std::move(word));
      }
    }
    synonyms_ = text::SynonymTable::build(*vectors_, words, config_.captions.synonyms);
  }
  validation_clips_ = captioned_clips(cache, Split::Val);
  // R@3 needs batches of more than 3 clips to mean anything.
  if (validation_clips_.size() < kMinValidationClips) validation_clips_.clear();
}

EvaluatorTrainer::~EvaluatorTrainer() = default;

int64_t EvaluatorTrainer::parameter_count() const {
  int64_t count = 0;
  for (const at::Tensor& p : model_->parameters()) count += p.numel();
  return count;
}

train::LossTerms EvaluatorTrainer::step(int64_t step) {
  // The step's random draws (dropout, piece dropout) depend on the seed and the step alone.
  torch::manual_seed(mix64(config_.seed ^ mix64(static_cast<uint64_t>(step))));
  const Batch batch = train_->next();
  const double lr = schedule_.at(step);
  const double share = batch.global_size > 0 ? static_cast<double>(batch.size) / batch.global_size : 1.0;
  model_->train();
  optimizer_->zero_grad();
  double loss_value = 0;
  if (batch.size > 0) {
    const tat::BatchTensors x = tat::to_tensors(batch).to(device_);
    const at::Tensor joints = skeleton_embeddings_->embed(batch);
    const text::TextBatch captions =
        captions_.read(rewritten_captions(batch.captions, step), vectors_, data_name_ + " captions");
    // Items whose normalized captions are equal match each other: compare caption ids, not strings, B^2 times.
    std::map<std::string, int64_t> caption_ids;
    std::vector<int64_t> ids;
    for (const std::string& caption : batch.captions) {
      ids.push_back(caption_ids.emplace(text::normalize_caption(caption), static_cast<int64_t>(caption_ids.size())).first->second);
    }
    const at::Tensor id_tensor = torch::tensor(ids, torch::kInt64);
    const at::Tensor same = id_tensor.unsqueeze(1) == id_tensor.unsqueeze(0);
    const ContrastiveBatch inputs{x.features, x.joint_mask, x.frame_mask, joints, captions.to(device_), same.to(device_)};
    const at::Tensor loss = contrastive_batch_loss(*model_, inputs, config_.captions.teacher_weight,
                                                   config_.captions.teacher_temperature);
    (loss * share).backward();
    loss_value = loss.item<double>() * share;
  }
  train::optimizer_step(*optimizer_, model_->parameters(), config_.optimizer.grad_clip, lr, ranks_);
  if (ranks_ != nullptr) {
    std::vector<at::Tensor> summed{torch::tensor({loss_value}, torch::kDouble)};
    ranks_->sum(summed);
    loss_value = summed[0][0].item<double>();
  }
  return {{"loss", loss_value}, {"scale", model_->logit_scale().item<double>()}, {"lr", lr}};
}

std::vector<std::string> EvaluatorTrainer::rewritten_captions(const std::vector<std::string>& captions,
                                                             int64_t step) const {
  const double probability = config_.captions.synonym_probability;
  if (probability == 0) return captions;
  SplitMix64 random(mix64(config_.seed ^ mix64(static_cast<uint64_t>(step) ^ kSynonymStream)));
  std::vector<std::string> out;
  for (const std::string& caption : captions) {
    std::string rewritten = synonyms_.rewrite(text::normalize_caption(caption), probability, random);
    // A synonym cut into more pieces can make a caption longer than the encoder reads: keep the caption then.
    const bool fits = captions_.count_pieces(rewritten) <= config_.model.text.max_pieces;
    out.push_back(fits ? std::move(rewritten) : caption);
  }
  return out;
}

std::optional<train::LossTerms> EvaluatorTrainer::validate() {
  if (validation_clips_.empty()) return std::nullopt;
  model_->eval();
  std::vector<std::string> captions;
  for (const int clip : validation_clips_) captions.push_back(cache_.clips[static_cast<size_t>(clip)].captions.front());
  const Embeddings text =
      to_embeddings(embed_captions(*model_, captions_, vectors_, captions, data_name_ + " val captions", device_));
  const Embeddings motion =
      to_embeddings(embed_clips(*model_, *owo_->encoder, vectors_, cache_, validation_clips_, device_));
  model_->train();
  RPrecisionOptions options;
  options.batch_size = std::min<int>(32, static_cast<int>(validation_clips_.size()));
  const RPrecision r = r_precision(text, motion, options);
  return train::LossTerms{{"val_r1", r.top_k[0].mean},
                          {"val_r2", r.top_k[1].mean},
                          {"val_r3", r.top_k[2].mean},
                          {"val_mm_dist", r.mm_dist.mean}};
}

train::TrainingSchedule EvaluatorTrainer::loop_schedule() const {
  return {config_.steps, config_.log_every, has_validation() ? config_.validate_every : 0, config_.checkpoint_every};
}

EvaluatorCheckpointInfo EvaluatorTrainer::info(int64_t step) const {
  EvaluatorCheckpointInfo info = info_;
  info.training_step = step;
  info.data = data_name_ + " (" + std::to_string(train_->clip_count()) + " captioned train clips)";
  info.fps = cache_.fps;
  info.window_frames = config_.data.window_frames;
  return info;
}

train::TrainingHooks EvaluatorTrainer::hooks(const std::string& out_dir) {
  train::TrainingHooks hooks;
  hooks.step = [this](int64_t step) { return this->step(step); };
  hooks.validate = [this](int64_t step) {
    train::LossTerms terms = *validate();
    const double r3 = terms[2].second;
    // A tie goes to the later, longer-trained model: R@3 reaches 1.0 early on a small validation split.
    if (info_.best_step == 0 || r3 >= info_.best_r_precision) {
      info_.best_step = step;
      info_.best_r_precision = r3;
      // Kept in memory until the next checkpoint writes it to <out>/best.
      if (!best_model_) best_model_ = Evaluator(config_.model);
      train::copy_module_tensors(*model_, *best_model_);
      best_pending_ = true;
    }
    terms.emplace_back("best_r3", info_.best_r_precision);
    return terms;
  };
  hooks.checkpoint = [this, out_dir](int64_t step) { save(out_dir, step); };
  return hooks;
}

void EvaluatorTrainer::save(const std::string& dir, int64_t step) {
  train::TrainingState state;
  state.model = "evaluator";
  state.step = step;
  state.config = train::write_config(config_);
  state.schedule = schedule_.to_json();
  state.data = train::batch_position(*train_);
  const fs::path kept = fs::path(dir) / kBestCheckpointDir;
  save_evaluator_checkpoint(dir, *model_, *owo_, captions_, info(step), [&](const std::string& temp) {
    train::write_training_state(temp, state, *optimizer_);
    const fs::path best = fs::path(temp) / kBestCheckpointDir;
    if (best_pending_) {
      EvaluatorCheckpointInfo best_info = info(info_.best_step);
      save_evaluator_checkpoint(best.string(), *best_model_, *owo_, captions_, best_info);
    } else if (fs::exists(kept / "config.json")) {
      fs::copy(kept, best, fs::copy_options::recursive);
    }
  });
  best_pending_ = false;
}

int64_t EvaluatorTrainer::resume(const std::string& dir) {
  const std::string state_path = (fs::path(dir) / train::kTrainingStateFile).string();
  LoadedEvaluator loaded = load_evaluator_checkpoint(dir);
  const train::TrainingState state = train::resumable_state(dir, "evaluator", loaded.info.training_step);
  train::check_resumable(state, train::write_config(config_), train::fields_that_may_change<EvaluatorTrainConfig>(),
                         state_path);
  train::copy_module_tensors(*loaded.model, *model_);
  train::load_optimizer_state(dir, *optimizer_, device_);
  schedule_ = train::LearningRateSchedule::resumed(config_.optimizer, state.schedule, state.step, config_.steps,
                                                   state_path);
  info_.best_step = loaded.info.best_step;
  info_.best_r_precision = loaded.info.best_r_precision;
  train::seek_batches(*train_, state.data, state_path);
  return state.step;
}

}  // namespace nec::evaluator

namespace nec::text {

void visit_fields(train::ConfigVisitor& v, SynonymOptions& c) {
  v.added_field("per_word", c.per_word, "most synonyms kept per caption word");
  v.added_field("min_cosine", c.min_cosine, "least cosine between a caption word and its synonym");
}

}  // namespace nec::text

// GPT training: config file, teacher-forced steps on cached tokens, validation, checkpoints, resume.
#include "nec/gpt/training.h"

#include "nec/gpt/checkpoint.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/random.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"
#include "nec/train/training_state.h"

#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>

namespace nec::gpt {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("GptTrainConfig: " + message);
}

// Validation batches hold this many items; skeleton features are computed this many skeletons at a time.
constexpr size_t kValidationBatch = 32;
constexpr size_t kSkeletonBatch = 16;

}  // namespace

void GptTrainConfig::validate() const {
  model.validate();
  try {
    optimizer.validate();
  } catch (const std::invalid_argument& e) {
    require(false, std::string("optimizer.") + e.what());
  }
  require(token_keep > 0 && token_keep <= 1, "token_keep must be in (0, 1]");
  require(caption_dropout >= 0 && caption_dropout < 1, "caption_dropout must be in [0, 1)");
  require(steps >= 1 && batch_size >= 1, "steps and batch_size must be >= 1");
  require(train::valid_cadence(log_every, validate_every, checkpoint_every), train::kCadenceRule);
}

void visit_fields(train::ConfigVisitor& v, GptTrainConfig& c) {
  v.object("model", c.model, "the transformer and its caption encoder");
  v.object("optimizer", c.optimizer, "AdamW, warm-up then cosine decay");
  v.field("token_keep", c.token_keep, "chance an input step keeps its codes, else random ones (T2M-GPT's pkeep)");
  v.field("caption_dropout", c.caption_dropout, "chance an item's caption is dropped (classifier-free guidance)");
  v.field("batch_size", c.batch_size, "items per step over all processes");
  train::visit_cadence_fields(v, c.steps, c.log_every, c.validate_every, c.checkpoint_every);
  v.field("seed", c.seed, "initial weights, batches and every step's random draws");
}

GptTrainConfig read_gpt_train_config(const std::string& path) {
  return train::read_config_file<GptTrainConfig>(path, "`nec train gpt --help` lists every field");
}

GptLoss gpt_loss(const GptLogits& logits, const at::Tensor& targets, int64_t global_items) {
  const int64_t b = targets.size(0), n = targets.size(1), k = logits.rest.size(3);
  const at::Tensor first_target = targets.select(2, 0);                     // (B, N)
  const at::Tensor first_scored = first_target >= 0;
  const at::Tensor first_ce = torch::nn::functional::cross_entropy(
      logits.first.reshape({b * n, k + 1}), first_target.clamp_min(0).reshape({b * n}),
      torch::nn::functional::CrossEntropyFuncOptions().reduction(torch::kNone)).view({b, n});
  at::Tensor total = (first_ce * first_scored).sum(1);
  at::Tensor count = first_scored.sum(1).to(torch::kFloat32);
  if (logits.rest.size(2) > 0) {
    const at::Tensor rest_target = targets.narrow(2, 1, targets.size(2) - 1);  // (B, N, R - 1)
    const at::Tensor rest_scored = rest_target >= 0;
    const at::Tensor rest_ce = torch::nn::functional::cross_entropy(
        logits.rest.reshape({-1, k}), rest_target.clamp_min(0).reshape({-1}),
        torch::nn::functional::CrossEntropyFuncOptions().reduction(torch::kNone)).view(rest_target.sizes());
    total = total + (rest_ce * rest_scored).sum({1, 2});
    count = count + rest_scored.sum({1, 2}).to(torch::kFloat32);
  }
  GptLoss out;
  out.loss = (total / count.clamp_min(1.0)).sum() / static_cast<double>(global_items);
  const at::Tensor right = (logits.first.argmax(2) == first_target) & first_scored;
  out.first_accuracy = right.sum().item<double>() / std::max<double>(1.0, first_scored.sum().item<double>());
  return out;
}

GptTrainer::GptTrainer(const GptTrainConfig& config, const DatasetCache& cache, std::string data_name,
                       tat::TokenizerSession& tokenizer, const std::string& tokenizer_dir,
                       text::CaptionReader captions, const text::WordVectors* vectors,
                       const c10::Device& device, const train::Communicator* ranks)
    : config_(config),
      cache_(cache),
      data_name_(std::move(data_name)),
      tokenizer_(tokenizer),
      captions_(std::move(captions)),
      vectors_(vectors),
      device_(device),
      ranks_(ranks),
      schedule_(config.optimizer, config.steps) {
  config_.validate();
  const tat::TatConfig& tat = tokenizer_.model.tokenizer->config();
  if (config_.model.codebook_layers != tat.quantizer.layers || config_.model.codebook_size != tat.quantizer.codebook_size) {
    throw std::invalid_argument("GptTrainConfig: model.codebook_layers / codebook_size must be the tokenizer's (" +
                                std::to_string(tat.quantizer.layers) + " x " + std::to_string(tat.quantizer.codebook_size) + ")");
  }
  std::ostream* log = ranks_ == nullptr || ranks_->is_main() ? &std::cout : nullptr;
  tokens_ = open_token_set(tokenizer_, cache_, tokenizer_dir, log);

  // Skeleton features, a few skeletons at a time (OwO's all-pairs edges grow with J^2).
  const text::WordVectors* owo_vectors = tokenizer_.vectors ? &*tokenizer_.vectors : nullptr;
  std::vector<at::Tensor> features;
  for (size_t begin = 0; begin < cache_.skeletons.size(); begin += kSkeletonBatch) {
    std::vector<Skeleton> skeletons;
    std::vector<std::vector<std::string>> names;
    for (size_t i = begin; i < std::min(cache_.skeletons.size(), begin + kSkeletonBatch); ++i) {
      skeletons.push_back(cache_.skeletons[i].skeleton);
      names.push_back(cache_.skeletons[i].canonical_names);
    }
    features.push_back(skeleton_features(*tokenizer_.model.owo->encoder, skeletons, names, owo_vectors).cpu());
  }
  skeleton_features_ = torch::cat(features);

  for (int row = 0; row < tokens_.size(); ++row) {
    const CacheClip& clip = cache_.clips[static_cast<size_t>(tokens_.clips[static_cast<size_t>(row)])];
    if (tokens_.steps[static_cast<size_t>(row)] < 1) continue;
    if (clip.split == Split::Train) train_rows_.push_back(row);
    if (clip.split == Split::Val) validation_rows_.push_back(row);
  }
  if (train_rows_.empty()) throw InputError(data_name_, 0, "the train split has no clip with a caption");
  captions_.check_corpus(cache_, data_name_);
  captions_.remember_corpus_encodings(cache_, train::kRememberedEncodingBytes);

  torch::manual_seed(config_.seed);
  model_ = TokenGpt(config_.model);
  if (vectors_ != nullptr && config_.model.text.word_dim > 0) {
    model_->text_encoder().init_piece_embeddings(*captions_.pieces(), *vectors_);
  }
  model_->to(device_);
  model_->train();
  optimizer_ = train::make_adamw(model_->parameters(), config_.optimizer);
}

GptTrainer::~GptTrainer() = default;

int64_t GptTrainer::parameter_count() const {
  int64_t count = 0;
  for (const at::Tensor& p : model_->parameters()) count += p.numel();
  return count;
}

GptBatch GptTrainer::make_batch(const std::vector<int>& rows, const std::vector<std::string>& captions,
                                const std::vector<int>& starts, const std::vector<int>& lengths,
                                const std::vector<bool>& drop_text) const {
  const int64_t b = static_cast<int64_t>(rows.size()), r = tokens_.layers, k = tokens_.codebook_size;
  const int64_t s = b == 0 ? 0 : *std::max_element(lengths.begin(), lengths.end());
  GptBatch batch;
  batch.captions = captions;
  batch.inputs = torch::zeros({b, s, r}, torch::kInt64);
  batch.targets = torch::full({b, s + 1, r}, -1, torch::kInt64);
  std::vector<int64_t> skeleton_rows;
  auto inputs = batch.inputs.accessor<int64_t, 3>();
  auto targets = batch.targets.accessor<int64_t, 3>();
  for (int64_t i = 0; i < b; ++i) {
    const int row = rows[static_cast<size_t>(i)], start = starts[static_cast<size_t>(i)], n = lengths[static_cast<size_t>(i)];
    const int steps = tokens_.steps[static_cast<size_t>(row)];
    const int32_t* codes = tokens_.codes_of(row);
    for (int t = 0; t <= n; ++t) {
      const int step = start + t;
      for (int64_t layer = 0; layer < r; ++layer) {
        if (step < steps) {
          const int64_t code = codes[static_cast<size_t>(step) * static_cast<size_t>(r) + static_cast<size_t>(layer)];
          if (t < n) inputs[i][t][layer] = code;
          targets[i][t][layer] = code;
        } else if (layer == 0) {
          targets[i][t][0] = k;  // the motion ends here
        }
      }
    }
    skeleton_rows.push_back(cache_.clips[static_cast<size_t>(tokens_.clips[static_cast<size_t>(row)])].skeleton);
  }
  batch.skeleton_features = skeleton_features_.index_select(0, torch::tensor(skeleton_rows, torch::kInt64));
  std::vector<int64_t> drops(drop_text.begin(), drop_text.end());
  batch.drop_text = torch::tensor(drops, torch::kInt64).to(torch::kBool);
  return batch;
}

GptBatch GptTrainer::batch(int64_t step, bool whole) const {
  SplitMix64 random(mix64(config_.seed ^ mix64(static_cast<uint64_t>(step))));
  const int64_t window = config_.model.max_steps - 1;
  std::vector<int> rows, starts, lengths;
  std::vector<std::string> captions;
  std::vector<bool> drops;
  const int world = ranks_ && !whole ? ranks_->world_size() : 1, rank = ranks_ && !whole ? ranks_->rank() : 0;
  for (int64_t item = 0; item < config_.batch_size; ++item) {
    const int row = train_rows_[random.below(train_rows_.size())];
    const CacheClip& clip = cache_.clips[static_cast<size_t>(tokens_.clips[static_cast<size_t>(row)])];
    const std::string& caption = clip.captions[random.below(clip.captions.size())];
    const int steps = tokens_.steps[static_cast<size_t>(row)];
    const int length = static_cast<int>(std::min<int64_t>(steps, window));
    // Crops may also end exactly at the clip's end, so that the end code is seen for long clips too.
    const int start = static_cast<int>(random.below(static_cast<uint64_t>(steps - length + 1)));
    const bool drop = random.chance(config_.caption_dropout);
    // Rank r takes items r, r + W, ...: its share of the same global batch.
    if (item % world != rank) continue;
    rows.push_back(row);
    captions.push_back(caption);
    starts.push_back(start);
    lengths.push_back(length);
    drops.push_back(drop);
  }
  return make_batch(rows, captions, starts, lengths, drops);
}

GptLoss teacher_forced_loss(TokenGptImpl& model, const text::TextBatch& captions, const GptBatch& batch,
                            double token_keep, int64_t global_items, const c10::Device& device) {
  const GptCondition condition =
      model.condition(captions.to(device), batch.skeleton_features.to(device), batch.drop_text.to(device));
  at::Tensor inputs = batch.inputs.to(device);
  if (model.is_training() && token_keep < 1) {
    // T2M-GPT's corruption: an input step's codes are replaced by random ones.
    const at::Tensor replace =
        torch::rand({inputs.size(0), inputs.size(1), 1}, inputs.options().dtype(torch::kFloat32)) >= token_keep;
    inputs = torch::where(replace, torch::randint_like(inputs, model.config().codebook_size), inputs);
  }
  const at::Tensor targets = batch.targets.to(device);
  return gpt_loss(model.forward(condition, inputs, targets), targets, global_items);
}

GptLoss GptTrainer::loss_of(const GptBatch& batch, int64_t global_items) {
  const text::TextBatch captions = captions_.read(batch.captions, vectors_, data_name_ + " captions");
  return teacher_forced_loss(*model_, captions, batch, config_.token_keep, global_items, device_);
}

train::LossTerms GptTrainer::step(int64_t step) {
  // The step's random draws (dropout, corruption) depend on the seed and the step alone.
  torch::manual_seed(mix64(config_.seed ^ mix64(static_cast<uint64_t>(step)) ^ 0x6770747472ull));
  const GptBatch share = batch(step);
  const double lr = schedule_.at(step);
  model_->train();
  optimizer_->zero_grad();
  double loss_value = 0, accuracy = 0;
  if (share.inputs.size(0) > 0) {
    const GptLoss loss = loss_of(share, config_.batch_size);
    loss.loss.backward();
    loss_value = loss.loss.item<double>();
    accuracy = loss.first_accuracy * static_cast<double>(share.inputs.size(0)) / static_cast<double>(config_.batch_size);
  }
  train::optimizer_step(*optimizer_, model_->parameters(), config_.optimizer.grad_clip, lr, ranks_);
  if (ranks_ != nullptr) {
    std::vector<at::Tensor> summed{torch::tensor({loss_value, accuracy}, torch::kDouble)};
    ranks_->sum(summed);
    loss_value = summed[0][0].item<double>();
    accuracy = summed[0][1].item<double>();
  }
  return {{"loss", loss_value}, {"accuracy", accuracy}, {"lr", lr}};
}

std::optional<train::LossTerms> GptTrainer::validate() {
  if (validation_rows_.empty()) return std::nullopt;
  model_->eval();
  torch::NoGradGuard no_grad;
  const int64_t window = config_.model.max_steps - 1;
  double loss = 0, right = 0;
  for (size_t begin = 0; begin < validation_rows_.size(); begin += kValidationBatch) {
    const size_t end = std::min(validation_rows_.size(), begin + kValidationBatch);
    std::vector<int> rows(validation_rows_.begin() + static_cast<std::ptrdiff_t>(begin),
                          validation_rows_.begin() + static_cast<std::ptrdiff_t>(end));
    std::vector<std::string> captions;
    std::vector<int> starts(rows.size(), 0), lengths;
    for (const int row : rows) {
      captions.push_back(cache_.clips[static_cast<size_t>(tokens_.clips[static_cast<size_t>(row)])].captions.front());
      lengths.push_back(static_cast<int>(std::min<int64_t>(tokens_.steps[static_cast<size_t>(row)], window)));
    }
    const GptLoss part = loss_of(make_batch(rows, captions, starts, lengths, std::vector<bool>(rows.size(), false)),
                                 static_cast<int64_t>(validation_rows_.size()));
    loss += part.loss.item<double>();
    right += part.first_accuracy * static_cast<double>(rows.size()) / static_cast<double>(validation_rows_.size());
  }
  model_->train();
  return train::LossTerms{{"val_loss", loss}, {"val_accuracy", right}};
}

train::TrainingSchedule GptTrainer::loop_schedule() const {
  return {config_.steps, config_.log_every, has_validation() ? config_.validate_every : 0, config_.checkpoint_every};
}

train::TrainingHooks GptTrainer::hooks(const std::string& out_dir) {
  train::TrainingHooks hooks;
  hooks.step = [this](int64_t step) { return this->step(step); };
  hooks.validate = [this](int64_t) { return *validate(); };
  hooks.checkpoint = [this, out_dir](int64_t step) { save(out_dir, step); };
  return hooks;
}

void GptTrainer::save(const std::string& dir, int64_t step) {
  train::TrainingState state;
  state.model = "gpt";
  state.step = step;
  state.config = train::write_config(config_);
  state.schedule = schedule_.to_json();
  state.data = {{"tokenizer_key", std::to_string(tokens_.tokenizer_key)}};
  GptCheckpointInfo info;
  info.fps = cache_.fps;
  info.training_step = step;
  info.data = data_name_ + " (" + std::to_string(train_rows_.size()) + " captioned train clips)";
  save_gpt_checkpoint(dir, *model_, captions_, tokenizer_.model, info,
                      [&](const std::string& temp) { train::write_training_state(temp, state, *optimizer_); });
}

int64_t GptTrainer::resume(const std::string& dir) {
  const std::string state_path = (fs::path(dir) / train::kTrainingStateFile).string();
  LoadedGpt loaded = load_gpt_checkpoint(dir);
  const train::TrainingState state = train::resumable_state(dir, "gpt", loaded.info.training_step);
  train::check_resumable(state, train::write_config(config_), train::fields_that_may_change<GptTrainConfig>(), state_path);
  train::copy_module_tensors(*loaded.model, *model_);
  train::load_optimizer_state(dir, *optimizer_, device_);
  schedule_ = train::LearningRateSchedule::resumed(config_.optimizer, state.schedule, state.step, config_.steps, state_path);
  return state.step;
}

}  // namespace nec::gpt

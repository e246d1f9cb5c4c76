// Diffusion training: config file, the two stages' steps, validation, checkpoints, resume.
#include "nec/diffusion/training.h"

#include "nec/diffusion/objective.h"
#include "nec/diffusion/sampling.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/random.h"
#include "nec/owo/checkpoint.h"
#include "nec/tat/batch_tensors.h"
#include "nec/tat/inference.h"
#include "nec/tat/model_space.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "nec/train/distributed.h"
#include "nec/train/training_state.h"

#include <ATen/CPUGeneratorImpl.h>
#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <stdexcept>

namespace nec::diffusion {
namespace {

namespace fs = std::filesystem;

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("DiffusionTrainConfig: " + message);
}

constexpr int kValidationBatch = 16;
constexpr int kValidationBatches = 4;      // the val loss reads at most this many batches
constexpr size_t kStatisticsClips = 512;   // data statistics from at most this many train clips
constexpr uint64_t kValidationSeed = 0x76616c6964ull;
constexpr size_t kSampledClips = 6;         // validation samples clips spread over the val split whole, as generation does
// A dropped caption still goes through the text encoder (then is replaced): any valid caption does.
constexpr const char* kPlaceholderCaption = "motion";

// Model space (1, T, J, C) of a clip's first `frames` frames as batches hold it.
at::Tensor clip_model_space(const DatasetCache& cache, int clip, int frames) {
  Features features = crop_at_start_heading(cache, clip, 0, frames);
  const at::Tensor theta =
      torch::from_blob(features.data.data(), {1, features.frame_count, features.joint_count, kFeatureSize}, torch::kFloat32);
  return tat::features_to_model_space(theta).clone();
}

}  // namespace

void DiffusionTrainConfig::validate() const {
  model.validate();
  try {
    optimizer.validate();
  } catch (const std::invalid_argument& e) {
    require(false, std::string("optimizer.") + e.what());
  }
  data.validate();
  require(data.window_frames <= model.max_frames, "data.window_frames must be <= model.max_frames");
  require(pose_frames >= 1, "pose_frames must be >= 1");
  require(caption_dropout >= 0 && caption_dropout < 1, "caption_dropout must be in [0, 1)");
  require(velocity_weight >= 0, "velocity_weight must be >= 0");
  require(steps >= 1 && batch_size >= 1, "steps and batch_size must be >= 1");
  require(train::valid_cadence(log_every, validate_every, checkpoint_every), train::kCadenceRule);
}

void visit_fields(train::ConfigVisitor& v, DiffusionTrainConfig& c) {
  v.object("model", c.model, "the denoiser (pose stage; the motion stage takes the pose model's)");
  v.object("optimizer", c.optimizer, "AdamW, warm-up then cosine decay");
  v.object("data", c.data, "training crops, joint-count buckets, rig augmentation");
  v.field("pose_frames", c.pose_frames, "pose stage: frames drawn from each item's crop, each a pose of its own");
  v.field("caption_dropout", c.caption_dropout, "chance an item's caption is dropped (classifier-free guidance)");
  v.field("velocity_weight", c.velocity_weight, "motion stage: weight of the frame-to-frame difference loss beside the x0 loss");
  v.field("train_pose_model", c.train_pose_model, "motion stage: train the pose model too (false: frozen, as the paper does)");
  v.field("batch_size", c.batch_size, "items per step over all processes");
  train::visit_cadence_fields(v, c.steps, c.log_every, c.validate_every, c.checkpoint_every);
  v.field("seed", c.seed, "initial weights, batches and every step's random draws");
}

DiffusionTrainConfig read_diffusion_train_config(const std::string& path) {
  return train::read_config_file<DiffusionTrainConfig>(path, "`nec train diffusion --help` lists every field");
}

at::Tensor denoising_loss(const at::Tensor& predicted, const at::Tensor& target, const at::Tensor& used,
                          int64_t global_items) {
  const at::Tensor weight = used.to(predicted.scalar_type());
  const at::Tensor per_item = ((predicted - target).square() * weight).sum({1, 2, 3}) / weight.sum({1, 2, 3}).clamp_min(1.0);
  return per_item.sum() / static_cast<double>(global_items);
}

at::Tensor velocity_loss(const at::Tensor& predicted, const at::Tensor& target, const at::Tensor& used,
                         int64_t global_items) {
  const int64_t frames = predicted.size(1);
  const auto velocity = [&](const at::Tensor& x) { return x.narrow(1, 1, frames - 1) - x.narrow(1, 0, frames - 1); };
  return denoising_loss(velocity(predicted), velocity(target), used.narrow(1, 1, frames - 1) & used.narrow(1, 0, frames - 1),
                        global_items);
}

DiffusionTrainer::DiffusionTrainer(const DiffusionTrainConfig& config, DiffusionStage stage, const DatasetCache& cache,
                                   std::string data_name, owo::OwoPretrainer owo, std::optional<LoadedDiffusion> pose,
                                   text::CaptionReader captions, const text::WordVectors* vectors,
                                   const c10::Device& device, const train::Communicator* ranks)
    : config_(config),
      stage_(stage),
      cache_(cache),
      data_name_(std::move(data_name)),
      owo_(std::move(owo)),
      captions_(std::move(captions)),
      vectors_(vectors),
      device_(device),
      ranks_(ranks),
      schedule_(pose ? pose->model->config().noise_steps : config.model.noise_steps),
      lr_schedule_(config.optimizer, config.steps) {
  if (stage_ == DiffusionStage::kMotion) {
    if (!pose) throw std::invalid_argument("the motion stage starts from a pose-stage checkpoint");
    config_.model = pose->model->config();
  }
  config_.validate();
  captions_.check_corpus(cache_, data_name_);
  train_ = std::make_unique<BatchLoader>(cache_, Split::Train,
                                         train::training_batches(config_.data, config_.batch_size, config_.seed, ranks_));
  if (train_->clip_count() < config_.batch_size) {
    throw InputError(data_name_, 0, "the train split has " + std::to_string(train_->clip_count()) +
                                        " clips, fewer than one batch of " + std::to_string(config_.batch_size));
  }
  const bool has_val = std::any_of(cache_.clips.begin(), cache_.clips.end(),
                                   [](const CacheClip& clip) { return clip.split == Split::Val; });
  if (has_val) {
    BatchOptions options;
    options.batch_size = kValidationBatch;
    options.crop_frames = static_cast<int>(config_.data.window_frames);
    options.shuffle = false;
    options.seed = kValidationSeed;
    validation_ = std::make_unique<BatchLoader>(cache_, Split::Val, options);
    const std::vector<int> val_clips = validation_->epoch_order(0);
    std::vector<int> spread;
    const size_t count = std::min<size_t>(kSampledClips, val_clips.size());
    for (size_t k = 0; k < count; ++k) spread.push_back(val_clips[k * val_clips.size() / count]);
    options.batch_size = 1;
    sampled_clips_ = std::make_unique<BatchLoader>(cache_, std::move(spread), options);
  }

  torch::manual_seed(config_.seed);
  if (stage_ == DiffusionStage::kPose) {
    model_ = MotionDenoiser(config_.model);
    if (vectors_ != nullptr && config_.model.text.word_dim > 0) model_->text_encoder().init_piece_embeddings(*captions_.pieces(), *vectors_);
    // Data statistics from train clips spread over the split.
    std::vector<int> clips;
    for (int i = 0; i < static_cast<int>(cache_.clips.size()); ++i) {
      if (cache_.clips[static_cast<size_t>(i)].split == Split::Train) clips.push_back(i);
    }
    std::vector<at::Tensor> motions;
    const size_t stride = std::max<size_t>(1, clips.size() / kStatisticsClips);
    for (size_t i = 0; i < clips.size(); i += stride) {
      const int frames = std::min<int>(cache_.clips[static_cast<size_t>(clips[i])].frame_count, static_cast<int>(config_.data.window_frames));
      motions.push_back(clip_model_space(cache_, clips[i], frames).squeeze(0));
    }
    model_->fit_statistics(motions);
  } else {
    model_ = pose->model;
    if (!config_.train_pose_model) freeze_pose_model(*model_);
  }
  model_->to(device_);
  train_mode();
  owo_->to(device_);
  owo_->eval();
  for (auto& parameter : owo_->parameters()) parameter.set_requires_grad(false);
  skeleton_embeddings_ =
      std::make_unique<tat::RememberedSkeletonEmbeddings>(owo_->encoder, vectors_, cache_, train::kRememberedEncodingBytes);
  captions_.remember_corpus_encodings(cache_, train::kRememberedEncodingBytes);
  optimizer_ = train::make_adamw(trained_parameters(), config_.optimizer);
}

DiffusionTrainer::~DiffusionTrainer() = default;

void DiffusionTrainer::train_mode() { set_training_mode(*model_, stage_); }

std::vector<at::Tensor> DiffusionTrainer::trained_parameters() {
  return diffusion::trained_parameters(*model_, stage_, config_.train_pose_model);
}

int64_t DiffusionTrainer::trained_parameter_count() const {
  int64_t count = 0;
  for (const at::Tensor& p : const_cast<DiffusionTrainer*>(this)->trained_parameters()) count += p.numel();
  return count;
}

SkeletonInputs DiffusionTrainer::skeleton_inputs(const Batch& batch, const tat::BatchTensors& x) {
  return make_skeleton_inputs(x.parents, x.offsets, x.joint_mask, skeleton_embeddings_->embed(batch).to(device_));
}

DenoisingCaptions DiffusionTrainer::read_captions(const Batch& batch, const std::function<bool(int64_t)>& drop) {
  std::vector<std::string> captions;
  std::vector<int64_t> dropped;
  for (int64_t i = 0; i < batch.size; ++i) {
    const std::string& caption = batch.captions[static_cast<size_t>(i)];
    captions.push_back(caption.empty() ? kPlaceholderCaption : caption);
    dropped.push_back(caption.empty() || drop(i) ? 1 : 0);
  }
  return {captions_.read(captions, vectors_, data_name_ + " captions").to(device_),
          torch::tensor(dropped, torch::kInt64).to(torch::kBool).to(device_)};
}

at::Tensor DiffusionTrainer::loss_of(const Batch& batch, bool validation, uint64_t draw_seed) {
  const tat::BatchTensors x = tat::to_tensors(batch).to(device_);
  const SkeletonInputs skeletons = skeleton_inputs(batch, x);
  const int64_t b = batch.size;
  // Each item draws its timestep, noise, frames and caption dropout from a stream of its own, seeded by
  // the step (or validation) and its place in the whole batch: a rank's share draws what one process would.
  const int64_t first = ranks_ != nullptr && !validation ? share_of(batch.global_size, ranks_->rank(), ranks_->world_size()).begin : 0;
  std::vector<at::Generator> streams;
  for (int64_t i = 0; i < b; ++i) {
    streams.push_back(at::make_generator<at::CPUGeneratorImpl>(mix64(draw_seed ^ mix64(static_cast<uint64_t>(first + i)))));
  }
  const auto per_item = [&](const std::function<at::Tensor(at::Generator&)>& draw) {
    std::vector<at::Tensor> rows;
    for (at::Generator& stream : streams) rows.push_back(draw(stream));
    return torch::stack(rows).to(device_);
  };

  DenoisingBatch drawn;
  drawn.skeletons = skeletons;
  drawn.motion = tat::features_to_model_space(x.features);  // (B, T, J, C)
  drawn.frame_mask = x.frame_mask;
  if (stage_ == DiffusionStage::kPose) {
    // Single frames: pose_frames real frames of each item, each a pose of its own.
    const at::Tensor real_frames = drawn.frame_mask.sum(1, /*keepdim=*/true).to(torch::kFloat32);  // (B, 1)
    const at::Tensor picks =
        (per_item([&](at::Generator& g) { return torch::rand({config_.pose_frames}, g); }) * real_frames).floor().to(torch::kInt64).clamp_max(drawn.motion.size(1) - 1);
    drawn.motion = torch::gather(drawn.motion, 1, picks.view({b, -1, 1, 1}).expand({b, config_.pose_frames, drawn.motion.size(2), drawn.motion.size(3)}));
    drawn.frame_mask = torch::ones({b, config_.pose_frames}, drawn.frame_mask.options());
  }
  drawn.t = (per_item([](at::Generator& g) { return torch::rand({1}, g); }).view({-1}) * static_cast<double>(schedule_.steps()))
                .floor().to(torch::kInt64).clamp_max(schedule_.steps() - 1);
  // Noise of the item's own joints, padded: the same whatever the batch's widest skeleton.
  const int64_t frames = drawn.motion.size(1), width = drawn.motion.size(2), channels = drawn.motion.size(3);
  std::vector<at::Tensor> noises;
  for (int64_t i = 0; i < b; ++i) {
    const int64_t item_joints = batch.joint_counts[static_cast<size_t>(i)];
    noises.push_back(torch::constant_pad_nd(torch::randn({frames, item_joints, channels}, streams[static_cast<size_t>(i)]),
                                            {0, 0, 0, width - item_joints}));
  }
  drawn.noise = torch::stack(noises).to(device_);

  const at::Tensor draws = per_item([](at::Generator& g) { return torch::rand({1}, g); }).view({-1}).cpu();
  DenoisingCaptions read = read_captions(
      batch, [&](int64_t i) { return !validation && draws[i].item<double>() < config_.caption_dropout; });
  drawn.text = std::move(read.text);
  drawn.drop_text = read.dropped;
  drawn.global_items = validation ? b : batch.global_size;
  return denoising_objective(*model_, schedule_, drawn, stage_, config_.velocity_weight);
}

train::LossTerms DiffusionTrainer::step(int64_t step) {
  // The step's other random draws (the caption encoder's dropout) depend on the seed and the step alone.
  torch::manual_seed(mix64(config_.seed ^ mix64(static_cast<uint64_t>(step)) ^ 0x646966667573ull));
  const Batch batch = train_->next();
  const double lr = lr_schedule_.at(step);
  train_mode();
  optimizer_->zero_grad();
  double loss_value = 0;
  if (batch.size > 0) {
    const at::Tensor loss = loss_of(batch, false, mix64(config_.seed ^ mix64(static_cast<uint64_t>(step))));
    loss.backward();
    loss_value = loss.item<double>();
  }
  const std::vector<at::Tensor> parameters = trained_parameters();
  train::optimizer_step(*optimizer_, parameters, config_.optimizer.grad_clip, lr, ranks_);
  if (ranks_ != nullptr) {
    std::vector<at::Tensor> summed{torch::tensor({loss_value}, torch::kDouble)};
    ranks_->sum(summed);
    loss_value = summed[0][0].item<double>();
  }
  return {{"loss", loss_value}, {"lr", lr}};
}

std::optional<train::LossTerms> DiffusionTrainer::validate() {
  if (!validation_) return std::nullopt;
  model_->eval();
  torch::NoGradGuard no_grad;
  double total = 0;
  int batches = 0;
  for (int index = 0; index < std::min(kValidationBatches, validation_->batches_per_epoch()); ++index, ++batches) {
    total += loss_of(validation_->batch(0, index), true, mix64(kValidationSeed ^ static_cast<uint64_t>(index))).item<double>();
  }
  // Clips spread over the val split sampled whole from their captions: do the bodies move as the real ones do?
  SampledTurning turning;
  DiffusionSamplingOptions options;
  options.seed = kValidationSeed;
  for (int index = 0; index < sampled_clips_->batches_per_epoch(); ++index) {
    const Batch clip = sampled_clips_->batch(0, index);
    const tat::BatchTensors x = tat::to_tensors(clip).to(device_);
    const DenoisingCaptions captions = read_captions(clip, [](int64_t) { return false; });
    turning.add(sampled_turning(*model_, schedule_, x, skeleton_inputs(clip, x),
                                model_->caption_condition(captions.text, captions.dropped), options));
  }
  train_mode();
  return train::LossTerms{{"val_loss", total / std::max(1, batches)},
                          {"val_sampled_pose_kept", turning.pose_kept()},
                          {"val_sampled_speed_kept", turning.speed_kept()}};
}

train::TrainingSchedule DiffusionTrainer::loop_schedule() const {
  return {config_.steps, config_.log_every, has_validation() ? config_.validate_every : 0, config_.checkpoint_every};
}

train::TrainingHooks DiffusionTrainer::hooks(const std::string& out_dir) {
  train::TrainingHooks hooks;
  hooks.step = [this](int64_t step) { return this->step(step); };
  hooks.validate = [this](int64_t) { return *validate(); };
  hooks.checkpoint = [this, out_dir](int64_t step) { save(out_dir, step); };
  return hooks;
}

void DiffusionTrainer::save(const std::string& dir, int64_t step) {
  train::TrainingState state;
  state.model = std::string("diffusion-") + to_string(stage_);
  state.step = step;
  state.config = train::write_config(config_);
  state.schedule = lr_schedule_.to_json();
  state.data = train::batch_position(*train_);
  DiffusionCheckpointInfo info;
  info.stage = stage_;
  info.fps = cache_.fps;
  info.training_step = step;
  info.data = data_name_ + " (" + std::to_string(train_->clip_count()) + " train clips)";
  save_diffusion_checkpoint(dir, *model_, *owo_, captions_, info,
                            [&](const std::string& temp) { train::write_training_state(temp, state, *optimizer_); });
}

int64_t DiffusionTrainer::resume(const std::string& dir) {
  const std::string state_path = (fs::path(dir) / train::kTrainingStateFile).string();
  LoadedDiffusion loaded = load_diffusion_checkpoint(dir);
  if (loaded.info.stage != stage_) {
    throw InputError(dir, 0, std::string("holds a ") + to_string(loaded.info.stage) + "-stage model; resume it with --stage " +
                                 to_string(loaded.info.stage));
  }
  const train::TrainingState state =
      train::resumable_state(dir, std::string("diffusion-") + to_string(stage_), loaded.info.training_step);
  train::check_resumable(state, train::write_config(config_), train::fields_that_may_change<DiffusionTrainConfig>(),
                         state_path);
  train::copy_module_tensors(*loaded.model, *model_);
  train::load_optimizer_state(dir, *optimizer_, device_);
  lr_schedule_ = train::LearningRateSchedule::resumed(config_.optimizer, state.schedule, state.step, config_.steps,
                                                      state_path);
  train::seek_batches(*train_, state.data, state_path);
  return state.step;
}

DiffusionTrainingInputs load_training_inputs(DiffusionStage stage, DiffusionTrainConfig& config,
                                             const std::string& resume_dir, const std::string& owo_dir,
                                             const std::string& pieces_path, const std::string& pose_dir,
                                             const std::string& glove_path) {
  DiffusionTrainingInputs inputs;
  std::optional<LoadedDiffusion> base;
  if (!resume_dir.empty()) {
    base = load_diffusion_checkpoint(resume_dir);
  } else if (stage == DiffusionStage::kMotion) {
    base = load_diffusion_checkpoint(pose_dir);
    if (base->info.stage != DiffusionStage::kPose) {
      throw InputError(pose_dir, 0, "is a motion-stage model; --pose takes the pose stage's checkpoint");
    }
  }
  if (base) {
    inputs.owo = base->owo;
    inputs.captions = base->captions;  // read before the first save replaces the directory
    if (stage == DiffusionStage::kPose) config.model = base->model->config();
  } else {
    inputs.owo = owo::load_owo_checkpoint(owo_dir).model;
    config.model.skeleton_dim = inputs.owo->encoder->config().dim;
    inputs.captions = text::CaptionReader::for_training(config.model.text, pieces_path);
  }
  const int64_t name_dim = inputs.owo->encoder->config().name_dim;
  const int64_t word_dim = base ? base->model->config().text.word_dim : config.model.text.word_dim;
  if (word_dim > 0 || name_dim > 0) {
    inputs.vectors.emplace(text::WordVectors::load_checked(glove_path, word_dim > 0 ? word_dim : name_dim));
    if (word_dim > 0 && name_dim > 0 && word_dim != name_dim) {
      throw InputError(inputs.vectors->path(), 0,
                       "the OwO encoder reads names of width " + std::to_string(name_dim) + ", model.text.word_dim is " +
                           std::to_string(word_dim) + ": set it to " + std::to_string(name_dim));
    }
  }
  if (stage == DiffusionStage::kMotion) inputs.pose = std::move(base);
  return inputs;
}

}  // namespace nec::diffusion

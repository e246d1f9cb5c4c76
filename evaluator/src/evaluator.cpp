// The evaluator model, its checkpoint directory, and embedding clips and captions.
#include "nec/evaluator/evaluator.h"

#include "nec/corpus/batch.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/owo/checkpoint.h"
#include "nec/tat/inference.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"

#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace nec::evaluator {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr const char* kArchitecture = "Evaluator";
constexpr const char* kConfigFile = "config.json";
constexpr const char* kTensorFile = "tensors.pt";
constexpr const char* kOwoDir = "owo";
constexpr const char* kTrainHint = "run `nec train evaluator` to make one";
constexpr int64_t kEmbedBatch = 32;  // clips or captions per forward pass when embedding

}  // namespace

void EvaluatorConfig::validate() const {
  motion.validate();
  text.validate();
  if (motion.output_dim != text.output_dim) {
    throw std::invalid_argument("EvaluatorConfig: motion.output_dim (" + std::to_string(motion.output_dim) +
                                ") and text.output_dim (" + std::to_string(text.output_dim) + ") must be equal");
  }
  if (!(initial_temperature > 0 && initial_temperature <= 1)) {
    throw std::invalid_argument("EvaluatorConfig: initial_temperature must be in (0, 1]");
  }
}

void visit_fields(train::ConfigVisitor& v, EvaluatorConfig& c) {
  v.object("motion", c.motion, "the motion encoder");
  v.object("text", c.text, "the text encoder");
  v.field("initial_temperature", c.initial_temperature, "starting temperature of the contrastive softmax (learnt)");
}

EvaluatorImpl::EvaluatorImpl(const EvaluatorConfig& config) : config_(config) {
  config_.validate();
  motion = register_module("motion", MotionEncoder(config_.motion));
  text = register_module("text", text::TextEncoder(config_.text));
  log_scale_ = register_parameter("log_scale", torch::tensor(std::log(1.0 / config_.initial_temperature)));
}

at::Tensor EvaluatorImpl::embed_motion(const at::Tensor& features, const at::Tensor& joint_mask,
                                       const at::Tensor& frame_mask, const at::Tensor& joint_embeddings) {
  return torch::nn::functional::normalize(motion->forward(features, joint_mask, frame_mask, joint_embeddings),
                                          torch::nn::functional::NormalizeFuncOptions().dim(1));
}

at::Tensor EvaluatorImpl::embed_text(const text::TextBatch& batch) {
  return torch::nn::functional::normalize(text->forward(batch).sentence,
                                          torch::nn::functional::NormalizeFuncOptions().dim(1));
}

at::Tensor EvaluatorImpl::logit_scale() const { return log_scale_.exp().clamp_max(100.0); }

void save_evaluator_checkpoint(const std::string& dir, EvaluatorImpl& model, owo::OwoPretrainerImpl& owo,
                               const text::CaptionReader& captions, const EvaluatorCheckpointInfo& info,
                               const std::function<void(const std::string&)>& extra) {
  train::write_checkpoint_directory(dir, "an evaluator checkpoint", [&](const std::string& temp) {
    const fs::path root(temp);
    owo::save_owo_checkpoint((root / kOwoDir).string(), owo, {info.training_step, info.data});
    train::save_module_tensors(model, (root / kTensorFile).string());
    if (extra) extra(temp);
    json config = {{"format", kEvaluatorCheckpointFormat},
                         {"version", kEvaluatorCheckpointVersion},
                         {"architecture", kArchitecture},
                         {"evaluator", train::write_config(model.config())},
                         {"fps", info.fps},
                         {"window_frames", info.window_frames},
                         {"training_step", info.training_step},
                         {"best_step", info.best_step},
                         {"best_r_precision", info.best_r_precision},
                         {"data", info.data},
                         {"tensors", kTensorFile},
                         {"owo", kOwoDir}};
    text::save_checkpoint_captions(temp, captions, config);
    write_file_atomic((root / kConfigFile).string(), config.dump(2) + "\n");
  });
}

LoadedEvaluator load_evaluator_checkpoint(const std::string& dir) {
  const train::CheckpointConfig config = train::read_checkpoint_config(
      dir, kEvaluatorCheckpointFormat, kEvaluatorCheckpointVersion, "an evaluator checkpoint", kTrainHint);
  const train::JsonFields fields = config.fields();
  const json& root = config.root;
  std::string architecture;
  fields.read(root, "architecture", "", architecture);
  if (architecture != kArchitecture) fields.fail("architecture '" + architecture + "' is not " + kArchitecture);
  const EvaluatorConfig model_config =
      train::read_config_object<EvaluatorConfig>(root, "evaluator", {config.path, fields.hint(), "", true});
  LoadedEvaluator loaded;
  fields.read(root, "fps", "", loaded.info.fps);
  fields.read(root, "window_frames", "", loaded.info.window_frames);
  fields.read(root, "training_step", "", loaded.info.training_step);
  fields.read(root, "best_step", "", loaded.info.best_step);
  fields.read(root, "best_r_precision", "", loaded.info.best_r_precision);
  fields.read(root, "data", "", loaded.info.data);
  const std::string tensor_file = fields.entry(root, "tensors");
  const std::string owo_dir = fields.entry(root, "owo");
  try {
    model_config.validate();
    loaded.model = Evaluator(model_config);
  } catch (const std::invalid_argument& error) {
    fields.fail(std::string(error.what()) + "; " + fields.hint());
  }
  train::load_module_tensors(*loaded.model, (fs::path(dir) / tensor_file).string(), kTrainHint);
  loaded.captions = text::load_checkpoint_captions(dir, root, model_config.text, fields);
  loaded.owo = owo::load_owo_checkpoint((fs::path(dir) / owo_dir).string()).model;
  if (loaded.owo->encoder->config().dim != model_config.motion.joint_embedding_dim) {
    fields.fail("motion.joint_embedding_dim is " + std::to_string(model_config.motion.joint_embedding_dim) +
                " but the OwO encoder has dim " + std::to_string(loaded.owo->encoder->config().dim) + "; " +
                fields.hint());
  }
  loaded.model->eval();
  loaded.owo->eval();
  return loaded;
}

EvaluatorSession::EvaluatorSession(LoadedEvaluator loaded, std::optional<text::WordVectors> vectors,
                                   const c10::Device& device)
    : loaded_(std::move(loaded)), vectors_(std::move(vectors)), device_(device) {
  loaded_.model->to(device_);
  loaded_.owo->to(device_);
}

at::Tensor embed_captions(EvaluatorImpl& model, const text::CaptionReader& reader, const text::WordVectors* vectors,
                          const std::vector<std::string>& captions, const std::string& where, const c10::Device& device) {
  c10::InferenceMode inference;
  std::vector<at::Tensor> parts;
  for (size_t begin = 0; begin < captions.size(); begin += kEmbedBatch) {
    const std::vector<std::string> part(
        captions.begin() + static_cast<std::ptrdiff_t>(begin),
        captions.begin() + static_cast<std::ptrdiff_t>(std::min(captions.size(), begin + kEmbedBatch)));
    const text::TextBatch batch = reader.read(part, vectors, where);
    parts.push_back(model.embed_text(batch.to(device)).cpu());
  }
  return parts.empty() ? torch::zeros({0, model.config().text.output_dim}) : torch::cat(parts);
}

Embeddings to_embeddings(const at::Tensor& embeddings) {
  const at::Tensor values = embeddings.detach().to(torch::kCPU, torch::kFloat64).contiguous();
  Embeddings out(values.size(0), values.size(1));
  const double* data = values.data_ptr<double>();
  for (int64_t i = 0; i < values.size(0); ++i) {
    for (int64_t k = 0; k < values.size(1); ++k) out(i, k) = data[i * values.size(1) + k];
  }
  return out;
}

at::Tensor EvaluatorSession::embed_captions(const std::vector<std::string>& captions, const std::string& where) {
  return evaluator::embed_captions(*loaded_.model, loaded_.captions, vectors_ ? &*vectors_ : nullptr, captions, where,
                                   device_);
}

namespace {

// Frames [begin, begin + count) of a prepared clip as Θ, turned to the clip's frame-0 heading (a training crop).
Features crop_prepared(const PreparedClip& prepared, double start_heading, int begin, int count) {
  const Motion& motion = prepared.clip.motion;
  Motion part = motion;
  const size_t joints = static_cast<size_t>(motion.joint_count), first = static_cast<size_t>(begin) * joints;
  const size_t last = first + static_cast<size_t>(count) * joints;
  part.frame_count = count;
  part.rotations.assign(motion.rotations.begin() + static_cast<std::ptrdiff_t>(first),
                        motion.rotations.begin() + static_cast<std::ptrdiff_t>(last));
  part.translations.assign(motion.translations.begin() + static_cast<std::ptrdiff_t>(first),
                           motion.translations.begin() + static_cast<std::ptrdiff_t>(last));
  Features crop = encode_features(prepared.clip.skeleton, part);
  turn_to_heading(crop, start_heading);
  return crop;
}

}  // namespace

at::Tensor EvaluatorSession::embed_motion_inputs(const std::vector<MotionInput>& inputs) {
  return embed_motions(*loaded_.model, *loaded_.owo->encoder, vectors_ ? &*vectors_ : nullptr, inputs.size(),
                       [&](size_t i) { return inputs[i]; }, device_);
}

at::Tensor EvaluatorSession::embed_clip(const PreparedClip& prepared) {
  const int frames = prepared.clip.motion.frame_count;
  const int count = std::min<int>(frames, static_cast<int>(loaded_.model->config().motion.max_frames()));
  return embed_clip_windows(prepared, {(frames - count) / 2}, count);
}

at::Tensor EvaluatorSession::embed_clip_windows(const PreparedClip& prepared, const std::vector<int>& starts, int frames) {
  const int clip_frames = prepared.clip.motion.frame_count;
  if (frames < 1 || frames > loaded_.model->config().motion.max_frames()) {
    throw std::invalid_argument("embed_clip_windows: windows of " + std::to_string(frames) +
                                " frames, the encoder takes 1 to " + std::to_string(loaded_.model->config().motion.max_frames()));
  }
  for (const int start : starts) {
    if (start < 0 || start + frames > clip_frames) {
      throw std::invalid_argument("embed_clip_windows: window [" + std::to_string(start) + ", " +
                                  std::to_string(start + frames) + ") outside the clip's " + std::to_string(clip_frames) +
                                  " frames");
    }
  }
  const double start_heading = root_heading(encode_features(prepared.clip.skeleton, prepared.clip.motion), 0);
  return embed_motions(*loaded_.model, *loaded_.owo->encoder, vectors_ ? &*vectors_ : nullptr, starts.size(), [&](size_t i) {
    return MotionInput{crop_prepared(prepared, start_heading, starts[i], frames), &prepared.clip.skeleton,
                       &prepared.canonical_names};
  }, device_);
}

at::Tensor EvaluatorSession::joint_embeddings(const Skeleton& skeleton, const std::vector<std::string>& canonical_names) {
  return tat::embed_skeletons(*loaded_.owo->encoder, {skeleton}, {canonical_names}, vectors_ ? &*vectors_ : nullptr)[0];
}

namespace {

// One crop of a clip to embed.
struct Crop {
  int clip = 0;
  int begin = 0;
  int frames = 0;
};

}  // namespace

at::Tensor embed_motions(EvaluatorImpl& model, owo::OwoEncoderImpl& owo, const text::WordVectors* vectors, size_t count,
                         const std::function<MotionInput(size_t)>& item, const c10::Device& device) {
  c10::InferenceMode inference;
  std::vector<at::Tensor> parts;
  for (size_t begin = 0; begin < count; begin += kEmbedBatch) {
    const size_t end = std::min(count, begin + kEmbedBatch);
    std::vector<MotionInput> inputs;
    for (size_t i = begin; i < end; ++i) inputs.push_back(item(i));
    const int64_t b = static_cast<int64_t>(inputs.size());
    int64_t frames = 1, joints = 1;
    for (const MotionInput& in : inputs) {
      frames = std::max<int64_t>(frames, in.features.frame_count);
      joints = std::max<int64_t>(joints, in.features.joint_count);
    }
    at::Tensor features = torch::zeros({b, frames, joints, kFeatureSize});
    at::Tensor joint_mask = torch::zeros({b, joints}, torch::kBool);
    at::Tensor frame_mask = torch::zeros({b, frames}, torch::kBool);
    std::vector<Skeleton> skeletons;
    std::vector<std::vector<std::string>> names;
    for (int64_t i = 0; i < b; ++i) {
      const Features& f = inputs[static_cast<size_t>(i)].features;
      const at::Tensor values =
          torch::from_blob(const_cast<float*>(f.data.data()), {f.frame_count, f.joint_count, kFeatureSize}, torch::kFloat32);
      features[i].narrow(0, 0, f.frame_count).narrow(1, 0, f.joint_count).copy_(values);
      joint_mask[i].narrow(0, 0, f.joint_count).fill_(true);
      frame_mask[i].narrow(0, 0, f.frame_count).fill_(true);
      skeletons.push_back(*inputs[static_cast<size_t>(i)].skeleton);
      names.push_back(*inputs[static_cast<size_t>(i)].canonical_names);
    }
    const at::Tensor embeddings = tat::embed_skeletons(owo, skeletons, names, vectors);
    parts.push_back(model.embed_motion(features.to(device), joint_mask.to(device), frame_mask.to(device), embeddings).cpu());
  }
  return parts.empty() ? torch::zeros({0, model.config().motion.output_dim}) : torch::cat(parts);
}

namespace {

at::Tensor embed_crops(EvaluatorImpl& model, owo::OwoEncoderImpl& owo, const text::WordVectors* vectors,
                       const DatasetCache& cache, const std::vector<Crop>& crops, const c10::Device& device) {
  return embed_motions(model, owo, vectors, crops.size(), [&](size_t i) {
    const Crop& crop = crops[i];
    const CachedSkeleton& skeleton = cache.skeleton_of(crop.clip);
    return MotionInput{crop_at_start_heading(cache, crop.clip, crop.begin, crop.frames), &skeleton.skeleton,
                       &skeleton.canonical_names};
  }, device);
}

}  // namespace

at::Tensor embed_clips(EvaluatorImpl& model, owo::OwoEncoderImpl& owo, const text::WordVectors* vectors,
                       const DatasetCache& cache, const std::vector<int>& clips, const c10::Device& device) {
  const int max_frames = static_cast<int>(model.config().motion.max_frames());
  std::vector<Crop> crops;
  for (const int clip : clips) {
    const int frames = cache.clips.at(static_cast<size_t>(clip)).frame_count;
    const int count = std::min(frames, max_frames);
    crops.push_back({clip, (frames - count) / 2, count});
  }
  return embed_crops(model, owo, vectors, cache, crops, device);
}

at::Tensor EvaluatorSession::embed_clips(const DatasetCache& cache, const std::vector<int>& clips) {
  return evaluator::embed_clips(*loaded_.model, *loaded_.owo->encoder, vectors_ ? &*vectors_ : nullptr, cache, clips,
                                device_);
}

at::Tensor EvaluatorSession::embed_windows(const DatasetCache& cache, int clip, const std::vector<int>& starts,
                                           int frames) {
  const int clip_frames = cache.clips.at(static_cast<size_t>(clip)).frame_count;
  if (frames < 1 || frames > loaded_.model->config().motion.max_frames()) {
    throw std::invalid_argument("embed_windows: windows of " + std::to_string(frames) + " frames, the encoder takes 1 to " +
                                std::to_string(loaded_.model->config().motion.max_frames()));
  }
  std::vector<Crop> crops;
  for (const int start : starts) {
    if (start < 0 || start + frames > clip_frames) {
      throw std::invalid_argument("embed_windows: window [" + std::to_string(start) + ", " +
                                  std::to_string(start + frames) + ") outside the clip's " +
                                  std::to_string(clip_frames) + " frames");
    }
    crops.push_back({clip, start, frames});
  }
  return embed_crops(*loaded_.model, *loaded_.owo->encoder, vectors_ ? &*vectors_ : nullptr, cache, crops, device_);
}

EvaluatorSession open_evaluator(const std::string& dir, const std::string& glove) {
  LoadedEvaluator loaded = load_evaluator_checkpoint(dir);
  const int64_t word_dim = loaded.model->config().text.word_dim;
  const int64_t name_dim = loaded.owo->encoder->config().name_dim;
  std::optional<text::WordVectors> vectors;
  if (word_dim > 0 || name_dim > 0) {
    if (word_dim > 0 && name_dim > 0 && word_dim != name_dim) {
      throw InputError(dir, 0, "the text encoder reads word vectors of width " + std::to_string(word_dim) +
                                   " and the OwO encoder of width " + std::to_string(name_dim) +
                                   "; the checkpoint is damaged, " + kTrainHint);
    }
    vectors.emplace(text::WordVectors::load_checked(glove, std::max(word_dim, name_dim)));
  }
  return EvaluatorSession(std::move(loaded), std::move(vectors), c10::kCPU);
}

}  // namespace nec::evaluator

// Whole-clip encode / decode with overlapping windows, and OwO joint embeddings.
#include "nec/tat/inference.h"

#include "nec/motion/error.h"
#include "nec/corpus/preprocess.h"
#include "nec/owo/graph.h"
#include "nec/owo/joint_names.h"
#include "nec/tat/fk.h"

#include <torch/torch.h>

#include <algorithm>
#include <stdexcept>

namespace nec::tat {
namespace {

int64_t round_up(int64_t value, int64_t multiple) { return (value + multiple - 1) / multiple * multiple; }

// Where the windows of a clip of `frames` frames lie.
struct WindowPlan {
  int64_t length = 0;           // frames per window
  std::vector<int64_t> starts;  // first frame of each window
  std::vector<int64_t> owned;   // (windows + 1) token-step boundaries: window k owns [owned[k], owned[k + 1])
  int64_t padded_frames() const { return starts.back() + length; }
};

WindowPlan plan_windows(int64_t frames, const WindowOptions& options, int64_t downsampling) {
  WindowPlan plan;
  if (frames <= options.window_frames) {
    plan.length = round_up(frames, downsampling);
    plan.starts = {0};
  } else {
    plan.length = options.window_frames;
    const int64_t hop = options.window_frames - options.overlap_frames;
    const int64_t count = (frames - options.window_frames + hop - 1) / hop + 1;
    for (int64_t k = 0; k < count; ++k) plan.starts.push_back(k * hop);
  }
  plan.owned.push_back(0);
  for (size_t k = 1; k < plan.starts.size(); ++k) {
    plan.owned.push_back((plan.starts[k] + options.overlap_frames / 2) / downsampling);
  }
  plan.owned.push_back(round_up(frames, downsampling) / downsampling);
  return plan;
}

void require_eval(const TokenizerImpl& tokenizer) {
  if (tokenizer.is_training()) throw std::logic_error("tat inference: call tokenizer->eval() first");
}

// (n, J, D) embeddings and (n, J) mask for n windows of one skeleton.
std::pair<at::Tensor, at::Tensor> skeleton_inputs(const at::Tensor& embeddings, int64_t joints, int64_t windows) {
  const at::Tensor mask = torch::ones({windows, joints}, torch::kBool);
  if (!embeddings.defined()) return {at::Tensor(), mask};
  if (embeddings.dim() != 2 || embeddings.size(0) != joints) {
    throw std::invalid_argument("tat inference: embeddings must be (J, D) with J = " + std::to_string(joints));
  }
  return {embeddings.unsqueeze(0).expand({windows, joints, embeddings.size(1)}).contiguous(), mask};
}

}  // namespace

void WindowOptions::validate(int64_t downsampling) const {
  if (window_frames <= 0 || window_frames % downsampling != 0) {
    throw std::invalid_argument("window_frames must be a positive multiple of the downsampling " +
                                std::to_string(downsampling) + ", got " + std::to_string(window_frames));
  }
  if (overlap_frames < 0 || overlap_frames % (2 * downsampling) != 0 || overlap_frames >= window_frames) {
    throw std::invalid_argument("overlap_frames must be a multiple of " + std::to_string(2 * downsampling) +
                                " below window_frames, got " + std::to_string(overlap_frames));
  }
}

at::Tensor embed_skeletons(owo::OwoEncoderImpl& encoder, const std::vector<Skeleton>& skeletons,
                           const std::vector<std::vector<std::string>>& canonical_names,
                           const text::WordVectors* vectors) {
  return encode_skeletons(encoder, skeletons, canonical_names, vectors).joints;
}

owo::OwoOutput encode_skeletons(owo::OwoEncoderImpl& encoder, const std::vector<Skeleton>& skeletons,
                                const std::vector<std::vector<std::string>>& canonical_names,
                                const text::WordVectors* vectors) {
  if (skeletons.size() != canonical_names.size()) {
    throw std::invalid_argument("embed_skeletons: one list of canonical names per skeleton");
  }
  const owo::OwoConfig& config = encoder.config();
  if (config.name_dim > 0) {
    if (vectors == nullptr) {
      throw InputError(text::default_word_vectors_path(), 0,
                       std::string("this model reads joint names and needs the word vectors; ") + text::kWordVectorHint);
    }
    if (vectors->dim() != config.name_dim) {
      throw InputError(vectors->path(), 0,
                       "word vectors of dimension " + std::to_string(vectors->dim()) + ", the model was trained with " +
                           std::to_string(config.name_dim));
    }
  }
  std::vector<owo::SkeletonGraph> graphs;
  graphs.reserve(skeletons.size());
  for (size_t i = 0; i < skeletons.size(); ++i) {
    const at::Tensor names =
        config.name_dim > 0 ? owo::name_embeddings(*vectors, canonical_names[i]) : at::Tensor();
    graphs.push_back(owo::make_skeleton_graph(skeletons[i], names, config.graph));
  }
  c10::InferenceMode inference;
  const c10::Device device = encoder.parameters().front().device();
  return encoder.forward(owo::collate(graphs, config.name_dim).to(device));
}

namespace {

// What the OwO encoder reads of a skeleton, as bytes: equal keys, equal embeddings.
std::string skeleton_key(const Skeleton& skeleton, const std::vector<std::string>& canonical_names) {
  std::string key;
  const auto append = [&key](const void* data, size_t bytes) { key.append(static_cast<const char*>(data), bytes); };
  for (const std::string& name : canonical_names) key.append(name).push_back('\0');
  append(skeleton.parents.data(), skeleton.parents.size() * sizeof(int));
  for (const Vec3& offset : skeleton.offsets) append(offset.data(), 3 * sizeof(double));
  for (const EndSite& end : skeleton.end_sites) {
    append(&end.parent, sizeof(int));
    append(end.offset.data(), 3 * sizeof(double));
  }
  return key;
}

}  // namespace

RememberedSkeletonEmbeddings::RememberedSkeletonEmbeddings(owo::OwoEncoder encoder, const text::WordVectors* vectors,
                                                           const DatasetCache& cache, size_t max_bytes)
    : encoder_(std::move(encoder)), vectors_(vectors) {
  // Rigs are embedded in chunks of similar size, smallest first, each bounded in items × joints² (OwO's edge
  // features are B × J × J × 16): one 140-joint centipede pads no chunk of 20-joint rigs.
  constexpr size_t kChunkCells = 64 * 48 * 48;
  std::vector<bool> used(cache.skeletons.size(), false);
  for (const CacheClip& clip : cache.clips) {
    if (clip.split != Split::Test) used.at(static_cast<size_t>(clip.skeleton)) = true;
  }
  std::vector<Skeleton> chunk;
  std::vector<std::vector<std::string>> names;
  size_t bytes = 0;
  const auto embed_chunk = [&] {
    const at::Tensor embedded = embed_skeletons(*encoder_, chunk, names, vectors_);
    for (size_t i = 0; i < chunk.size(); ++i) {
      at::Tensor row = embedded[static_cast<int64_t>(i)].narrow(0, 0, chunk[i].joint_count()).clone();
      bytes += static_cast<size_t>(row.numel()) * sizeof(float);
      if (bytes > max_bytes) return false;
      kept_.emplace(skeleton_key(chunk[i], names[i]), std::move(row));
    }
    chunk.clear();
    names.clear();
    return true;
  };
  std::vector<size_t> order;
  for (size_t s = 0; s < cache.skeletons.size(); ++s) {
    if (used[s]) order.push_back(s);
  }
  const auto joints = [&](size_t s) { return static_cast<size_t>(cache.skeletons[s].skeleton.joint_count()); };
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return joints(a) < joints(b); });
  for (size_t s : order) {
    if (!chunk.empty() && (chunk.size() + 1) * joints(s) * joints(s) > kChunkCells && !embed_chunk()) return;
    chunk.push_back(cache.skeletons[s].skeleton);
    names.push_back(cache.skeletons[s].canonical_names);
  }
  if (!chunk.empty()) embed_chunk();
}

RememberedSkeletonEmbeddings::~RememberedSkeletonEmbeddings() = default;

at::Tensor RememberedSkeletonEmbeddings::embed(const Batch& batch) {
  const size_t items = batch.skeletons.size();
  std::vector<at::Tensor> rows(items);
  std::vector<size_t> missing;  // items embedded now
  std::vector<Skeleton> skeletons;
  std::vector<std::vector<std::string>> names;
  for (size_t i = 0; i < items; ++i) {
    const bool augmented = i < batch.augmented.size() && batch.augmented[i] != 0;
    const auto kept = augmented ? kept_.end() : kept_.find(skeleton_key(batch.skeletons[i], batch.canonical_names[i]));
    if (kept != kept_.end()) {
      rows[i] = kept->second;
      continue;
    }
    missing.push_back(i);
    skeletons.push_back(batch.skeletons[i]);
    names.push_back(batch.canonical_names[i]);
  }
  if (missing.size() == items) return embed_skeletons(*encoder_, skeletons, names, vectors_).clone();
  if (!missing.empty()) {
    const at::Tensor fresh = embed_skeletons(*encoder_, skeletons, names, vectors_);
    for (size_t m = 0; m < missing.size(); ++m) {
      rows[missing[m]] = fresh[static_cast<int64_t>(m)].narrow(0, 0, skeletons[m].joint_count()).clone();
    }
  }
  int64_t most_joints = 0;
  for (const at::Tensor& row : rows) most_joints = std::max(most_joints, row.size(0));
  at::Tensor out = torch::zeros({static_cast<int64_t>(items), most_joints, rows.front().size(1)}, rows.front().options());
  for (size_t i = 0; i < items; ++i) out[static_cast<int64_t>(i)].narrow(0, 0, rows[i].size(0)).copy_(rows[i]);
  return out;
}

at::Tensor encode_clip(TokenizerImpl& tokenizer, const Features& features, const at::Tensor& embeddings,
                       const WindowOptions& windows) {
  require_eval(tokenizer);
  const int64_t r = tokenizer.config().downsampling();
  windows.validate(r);
  const int64_t frames = features.frame_count, joints = features.joint_count;
  if (frames < 1) throw std::invalid_argument("encode_clip: the clip has no frames");
  const WindowPlan plan = plan_windows(frames, windows, r);
  const int64_t count = static_cast<int64_t>(plan.starts.size());

  // The clip padded by holding its last pose, and its absolute root height per frame.
  const at::Tensor clip =
      torch::from_blob(const_cast<float*>(features.data.data()), {frames, joints, kFeatureSize}, torch::kFloat32);
  at::Tensor padded = torch::cat({clip, clip.slice(0, frames - 1).expand({plan.padded_frames() - frames, joints,
                                                                          kFeatureSize})});
  padded.slice(0, frames).select(1, 0).slice(1, 0, 3).zero_();  // no root motion while holding
  const at::Tensor height = padded.select(1, 0).select(1, 1).cumsum(0);

  std::vector<at::Tensor> crops;
  for (int64_t start : plan.starts) {
    at::Tensor crop = padded.slice(0, start, start + plan.length).clone();
    if (start > 0) {  // as a training crop: frame 0 holds (0, height, 0)
      at::Tensor root_delta = crop[0][0].slice(0, 0, 3);
      root_delta.zero_();
      root_delta[1].copy_(height[start]);
    }
    crops.push_back(crop);
  }
  c10::InferenceMode inference;
  const auto [batch_embeddings, mask] = skeleton_inputs(embeddings, joints, count);
  const at::Tensor latent = tokenizer.encode(align_window_headings(torch::stack(crops)), mask, batch_embeddings);
  const at::Tensor codes = tokenizer.quantize(latent).codes;  // (n, length / r, R)

  std::vector<at::Tensor> owned;
  for (int64_t k = 0; k < count; ++k) {
    const int64_t first_step = plan.starts[k] / r;
    owned.push_back(codes[k].slice(0, plan.owned[k] - first_step, plan.owned[k + 1] - first_step));
  }
  return torch::cat(owned).contiguous();
}

Features decode_clip(TokenizerImpl& tokenizer, const at::Tensor& codes, int frame_count, const at::Tensor& embeddings,
                     const Skeleton& skeleton, double fps, const WindowOptions& windows) {
  require_eval(tokenizer);
  const int64_t r = tokenizer.config().downsampling();
  windows.validate(r);
  if (frame_count < 1) throw std::invalid_argument("decode_clip: frame_count must be positive");
  const int64_t steps = round_up(frame_count, r) / r;
  if (codes.dim() != 2 || codes.size(0) != steps) {
    throw std::invalid_argument("decode_clip: codes must be (" + std::to_string(steps) + ", R) for " +
                                std::to_string(frame_count) + " frames");
  }
  const WindowPlan plan = plan_windows(frame_count, windows, r);
  const int64_t count = static_cast<int64_t>(plan.starts.size());
  const int64_t window_steps = plan.length / r;
  const int64_t joint_count = skeleton.joint_count();

  c10::InferenceMode inference;
  std::vector<at::Tensor> window_codes;
  for (int64_t start : plan.starts) {
    const at::Tensor index = torch::arange(start / r, start / r + window_steps, torch::kLong).clamp_max(steps - 1);
    window_codes.push_back(codes.index_select(0, index));
  }
  const auto [batch_embeddings, mask] = skeleton_inputs(embeddings, joint_count, count);
  const at::Tensor latent = tokenizer.codes_to_latent(torch::stack(window_codes));
  // Each window is decoded facing 0 at its frame 0: turn it to go on from the one before.
  at::Tensor decoded = continue_window_headings(
      tokenizer.decode(latent, mask, batch_embeddings).to(torch::kFloat32), plan.starts);  // (n, length, J, 9)
  // Blend in a space where windows agree: absolute root height instead of Δy.
  decoded.select(2, 0).select(2, 1).copy_(decoded.select(2, 0).select(2, 1).cumsum(1));

  const int64_t total = plan.padded_frames();
  at::Tensor sum = torch::zeros({total, joint_count, kFeatureSize});
  at::Tensor weight_sum = torch::zeros({total});
  const double overlap = static_cast<double>(windows.overlap_frames);
  for (int64_t k = 0; k < count; ++k) {
    at::Tensor weight = torch::ones({plan.length});
    auto w = weight.accessor<float, 1>();
    for (int64_t f = 0; f < plan.length; ++f) {
      if (k > 0 && f < windows.overlap_frames) w[f] = static_cast<float>((f + 0.5) / overlap);
      if (k + 1 < count && f >= plan.length - windows.overlap_frames) {
        w[f] = static_cast<float>((plan.length - f - 0.5) / overlap);
      }
    }
    sum.slice(0, plan.starts[k], plan.starts[k] + plan.length) += decoded[k] * weight.view({-1, 1, 1});
    weight_sum.slice(0, plan.starts[k], plan.starts[k] + plan.length) += weight;
  }
  at::Tensor blended = (sum / weight_sum.view({-1, 1, 1})).slice(0, 0, frame_count).contiguous();
  at::Tensor height = blended.select(1, 0).select(1, 1).clone();
  blended.select(1, 0).select(1, 1).slice(0, 1).copy_(height.slice(0, 1) - height.slice(0, 0, frame_count - 1));

  Features out;
  out.frame_count = frame_count;
  out.joint_count = joint_count;
  out.fps = fps;
  out.data.assign(blended.data_ptr<float>(), blended.data_ptr<float>() + blended.numel());
  face_forward_at_start(out, skeleton);
  return out;
}

}  // namespace nec::tat

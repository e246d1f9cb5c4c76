// Token codes of a cache's captioned clips under one tokenizer, stored beside the cache; skeleton features.
#include "nec/gpt/token_set.h"

#include "nec/gpt/model.h"
#include "nec/motion/byte_io.h"
#include "nec/motion/files.h"
#include "nec/train/checkpoint_io.h"

#include <torch/torch.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace nec::gpt {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'N', 'E', 'C', 'T', 'O', 'K', 'S', '\0'};

std::string token_set_path(const DatasetCache& cache, uint64_t tokenizer_key) {
  char name[64];
  std::snprintf(name, sizeof name, "gpt-tokens-%016llx.bin", static_cast<unsigned long long>(tokenizer_key));
  return (fs::path(cache.directory) / name).string();
}

}  // namespace

TokenSet build_token_set(tat::TokenizerSession& session, const DatasetCache& cache) {
  const tat::TatConfig& config = session.model.tokenizer->config();
  TokenSet set;
  set.layers = static_cast<int>(config.quantizer.layers);
  set.codebook_size = static_cast<int>(config.quantizer.codebook_size);
  set.downsampling = static_cast<int>(config.downsampling());
  set.cache_key = cache_key(cache);
  std::vector<at::Tensor> skeleton_embeddings(cache.skeletons.size());
  for (int clip = 0; clip < cache.clip_count(); ++clip) {
    const CacheClip& c = cache.clips[static_cast<size_t>(clip)];
    if (c.captions.empty()) continue;
    at::Tensor& embeddings = skeleton_embeddings[static_cast<size_t>(c.skeleton)];
    const CachedSkeleton& skeleton = cache.skeletons[static_cast<size_t>(c.skeleton)];
    if (!embeddings.defined()) embeddings = session.embed(skeleton.skeleton, skeleton.canonical_names);
    const at::Tensor codes =
        tat::encode_clip(*session.model.tokenizer, cache.features(clip), embeddings, session.windows)
            .to(torch::kInt32)
            .contiguous();
    set.clips.push_back(clip);
    set.steps.push_back(static_cast<int>(codes.size(0)));
    set.offsets.push_back(set.codes.size());
    set.codes.insert(set.codes.end(), codes.data_ptr<int32_t>(), codes.data_ptr<int32_t>() + codes.numel());
  }
  return set;
}

std::string serialize(const TokenSet& tokens) {
  std::string out(kMagic, sizeof kMagic);
  append_value(out, kTokenSetVersion);
  append_value(out, static_cast<uint32_t>(tokens.layers));
  append_value(out, static_cast<uint32_t>(tokens.codebook_size));
  append_value(out, static_cast<uint32_t>(tokens.downsampling));
  append_value(out, tokens.cache_key);
  append_value(out, tokens.tokenizer_key);
  append_value(out, static_cast<uint64_t>(tokens.clips.size()));
  for (size_t i = 0; i < tokens.clips.size(); ++i) {
    append_value(out, static_cast<uint32_t>(tokens.clips[i]));
    append_value(out, static_cast<uint32_t>(tokens.steps[i]));
  }
  append_values(out, tokens.codes);
  return out;
}

TokenSet deserialize_token_set(const std::string& bytes, const std::string& path) {
  ByteReader in(bytes, path, "the token set");
  if (in.text(sizeof kMagic) != std::string(kMagic, sizeof kMagic)) in.fail("is not a token set (bad magic)");
  if (in.get<uint32_t>() != kTokenSetVersion) in.fail("is of another version");
  TokenSet set;
  set.layers = static_cast<int>(in.get<uint32_t>());
  set.codebook_size = static_cast<int>(in.get<uint32_t>());
  set.downsampling = static_cast<int>(in.get<uint32_t>());
  set.cache_key = in.get<uint64_t>();
  set.tokenizer_key = in.get<uint64_t>();
  const uint64_t clips = in.get<uint64_t>();
  if (set.layers < 1 || set.codebook_size < 1 || clips > bytes.size()) in.fail("is damaged");
  size_t total = 0;
  for (uint64_t i = 0; i < clips; ++i) {
    set.clips.push_back(static_cast<int>(in.get<uint32_t>()));
    set.steps.push_back(static_cast<int>(in.get<uint32_t>()));
    set.offsets.push_back(total);
    total += static_cast<size_t>(set.steps.back()) * static_cast<size_t>(set.layers);
    if (i > 0 && set.clips[i] <= set.clips[i - 1]) in.fail("is damaged (clips out of order)");
  }
  set.codes = in.values<int32_t>(total);
  if (!in.done()) in.fail("has trailing bytes");
  for (const int32_t code : set.codes) {
    if (code < 0 || code >= set.codebook_size) in.fail("is damaged (a code out of range)");
  }
  return set;
}

TokenSet open_token_set(tat::TokenizerSession& session, const DatasetCache& cache, const std::string& tokenizer_dir,
                        std::ostream* log) {
  const uint64_t tokenizer = train::checkpoint_key(tokenizer_dir);
  const uint64_t cache_hash = cache_key(cache);
  std::string path;
  if (!cache.directory.empty()) {
    path = token_set_path(cache, tokenizer);
    if (fs::exists(path)) {
      try {
        TokenSet stored = deserialize_token_set(read_file(path, size_t{1} << 34), path);
        if (stored.cache_key == cache_hash && stored.tokenizer_key == tokenizer) return stored;
        if (log) *log << path << ": of another cache or tokenizer; rebuilt\n";
      } catch (const InputError& e) {
        if (log) *log << e.what() << "\n";
      }
    }
  }
  TokenSet set = build_token_set(session, cache);
  set.tokenizer_key = tokenizer;
  if (path.empty()) return set;
  try {
    write_file_atomic(path, serialize(set));
    if (log) *log << "tokens of " << set.size() << " captioned clips stored in " << path << "\n";
  } catch (const std::exception& e) {
    if (log) *log << "the tokens are not stored (" << e.what() << "); they are computed on every run\n";
  }
  return set;
}

at::Tensor skeleton_features(owo::OwoEncoderImpl& encoder, const std::vector<Skeleton>& skeletons,
                             const std::vector<std::vector<std::string>>& canonical_names,
                             const text::WordVectors* vectors) {
  const owo::OwoOutput encoded = tat::encode_skeletons(encoder, skeletons, canonical_names, vectors);
  const at::Tensor& joints = encoded.joints;  // (B, J, D), zero at padding
  const at::Tensor& node = encoded.skeleton;  // (B, D)
  const c10::Device device = joints.device();
  std::vector<int64_t> counts;
  for (const Skeleton& s : skeletons) counts.push_back(s.joint_count());
  const at::Tensor count = torch::tensor(counts, torch::kFloat32).to(device).view({-1, 1});
  const at::Tensor real = (torch::arange(joints.size(1), count.options()).view({1, -1}) < count).unsqueeze(-1);
  const at::Tensor mean = (joints * real).sum(1) / count;
  const at::Tensor max = joints.masked_fill(real.logical_not(), -1e9).amax(1);
  return torch::cat({node, mean, max, count.log()}, 1).clone();
}

}  // namespace nec::gpt

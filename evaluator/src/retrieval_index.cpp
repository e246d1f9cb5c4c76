// The retrieval index: build, store, load, and nearest neighbours.
#include "nec/evaluator/retrieval_index.h"

#include "nec/motion/byte_io.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/hash.h"
#include "nec/train/checkpoint_io.h"

#include <torch/torch.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <set>

namespace nec::evaluator {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'N', 'E', 'C', 'R', 'I', 'D', 'X', '\0'};

std::vector<float> tensor_values(const at::Tensor& embeddings) {
  const at::Tensor values = embeddings.detach().to(torch::kCPU, torch::kFloat32).contiguous();
  return std::vector<float>(values.data_ptr<float>(), values.data_ptr<float>() + values.numel());
}

std::vector<Match> best_rows(const at::Tensor& query, const std::vector<float>& rows, int dim, int k,
                             const std::function<bool(int)>& keep) {
  const at::Tensor q = query.detach().to(torch::kCPU, torch::kFloat32).reshape({-1}).contiguous();
  if (q.numel() != dim) {
    throw std::invalid_argument("retrieval query of width " + std::to_string(q.numel()) + ", the index holds " +
                                std::to_string(dim));
  }
  const float* query_values = q.data_ptr<float>();
  const size_t count = dim > 0 ? rows.size() / static_cast<size_t>(dim) : 0;
  std::vector<Match> scored;
  scored.reserve(count);
  for (size_t r = 0; r < count; ++r) {
    if (keep && !keep(static_cast<int>(r))) continue;
    const float* row = rows.data() + r * static_cast<size_t>(dim);
    float dot = 0.f;
    for (int d = 0; d < dim; ++d) dot += row[d] * query_values[d];
    scored.push_back({static_cast<int>(r), dot});
  }
  const size_t top = std::min(scored.size(), static_cast<size_t>(std::max(k, 0)));
  std::partial_sort(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(top), scored.end(),
                    [](const Match& a, const Match& b) { return a.score > b.score || (a.score == b.score && a.row < b.row); });
  scored.resize(top);
  return scored;
}

}  // namespace

std::vector<Match> RetrievalIndex::nearest_clips(const at::Tensor& query, int k,
                                                 const std::function<bool(int clip)>& keep) const {
  std::function<bool(int)> keep_row;
  if (keep) keep_row = [&](int row) { return keep(clips[static_cast<size_t>(row)]); };
  return best_rows(query, clip_embeddings, dim, k, keep_row);
}

std::vector<Match> RetrievalIndex::nearest_captions(const at::Tensor& query, int k) const {
  return best_rows(query, caption_embeddings, dim, k, {});
}

std::string retrieval_index_path(const DatasetCache& cache, uint64_t evaluator_key) {
  char name[64];
  std::snprintf(name, sizeof name, "retrieval-%016llx.index", static_cast<unsigned long long>(evaluator_key));
  return (fs::path(cache.directory) / name).string();
}

RetrievalIndex build_retrieval_index(EvaluatorSession& session, const DatasetCache& cache, uint64_t evaluator_key) {
  RetrievalIndex index;
  index.cache_key = cache_key(cache);
  index.evaluator_key = evaluator_key;
  index.dim = static_cast<int>(session.dim());
  for (int clip = 0; clip < cache.clip_count(); ++clip) index.clips.push_back(clip);
  index.clip_embeddings = tensor_values(session.embed_clips(cache, index.clips));
  std::set<std::string> seen;
  for (const CacheClip& clip : cache.clips) {
    for (const std::string& caption : clip.captions) {
      if (seen.insert(caption).second) index.captions.push_back(caption);
    }
  }
  index.caption_embeddings = tensor_values(session.embed_captions(index.captions, "cache captions"));
  return index;
}

std::string serialize(const RetrievalIndex& index) {
  std::string out(kMagic, sizeof kMagic);
  append_value(out, kRetrievalIndexVersion);
  append_value(out, static_cast<uint32_t>(index.dim));
  append_value(out, index.cache_key);
  append_value(out, index.evaluator_key);
  append_value(out, static_cast<uint64_t>(index.clips.size()));
  append_value(out, static_cast<uint64_t>(index.captions.size()));
  for (const int clip : index.clips) append_value(out, static_cast<uint32_t>(clip));
  append_values(out, index.clip_embeddings);
  for (const std::string& caption : index.captions) {
    append_value(out, static_cast<uint32_t>(caption.size()));
    out += caption;
  }
  append_values(out, index.caption_embeddings);
  return out;
}

RetrievalIndex deserialize_retrieval_index(const std::string& bytes, const std::string& path) {
  if (bytes.compare(0, sizeof kMagic, kMagic, sizeof kMagic) != 0) {
    throw InputError(path, 0, "not a retrieval index (bad magic); it will be rebuilt");
  }
  ByteReader in(bytes, path, "the retrieval index");
  in.text(sizeof kMagic);
  if (in.get<uint32_t>() != kRetrievalIndexVersion) throw InputError(path, 0, "another index version; it will be rebuilt");
  RetrievalIndex index;
  index.dim = static_cast<int>(in.get<uint32_t>());
  index.cache_key = in.get<uint64_t>();
  index.evaluator_key = in.get<uint64_t>();
  const uint64_t clips = in.get<uint64_t>(), captions = in.get<uint64_t>();
  if (index.dim < 1 || clips > bytes.size() || captions > bytes.size()) {
    throw InputError(path, 0, "the retrieval index is damaged; it will be rebuilt");
  }
  for (uint64_t i = 0; i < clips; ++i) index.clips.push_back(static_cast<int>(in.get<uint32_t>()));
  index.clip_embeddings = in.values<float>(clips * static_cast<uint64_t>(index.dim));
  for (uint64_t i = 0; i < captions; ++i) index.captions.push_back(in.text(in.get<uint32_t>()));
  index.caption_embeddings = in.values<float>(captions * static_cast<uint64_t>(index.dim));
  if (!in.done()) throw InputError(path, 0, "the retrieval index has trailing bytes; it will be rebuilt");
  return index;
}

OpenedIndex open_retrieval_index(EvaluatorSession& session, const DatasetCache& cache, const std::string& evaluator_dir) {
  OpenedIndex opened;
  const uint64_t evaluator = train::checkpoint_key(evaluator_dir);
  const uint64_t cache_hash = cache_key(cache);
  if (!cache.directory.empty()) {
    opened.path = retrieval_index_path(cache, evaluator);
    if (fs::exists(opened.path)) {
      try {
        RetrievalIndex stored = deserialize_retrieval_index(read_file(opened.path, size_t{1} << 34), opened.path);
        if (stored.cache_key == cache_hash && stored.evaluator_key == evaluator && stored.dim == session.dim()) {
          opened.index = std::move(stored);
          return opened;
        }
        opened.note = "the stored index is of another cache or evaluator; rebuilt";
      } catch (const InputError& e) {
        opened.note = e.what();
      }
    }
  }
  opened.index = build_retrieval_index(session, cache, evaluator);
  opened.built = true;
  if (opened.path.empty()) return opened;
  try {
    write_file_atomic(opened.path, serialize(opened.index));
    opened.stored = true;
  } catch (const std::exception& e) {
    opened.note = std::string("the index is not stored (") + e.what() + "); it is rebuilt on every run";
  }
  return opened;
}

}  // namespace nec::evaluator

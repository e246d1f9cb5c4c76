// The retrieval index: build, store, load, and nearest neighbours.
#include "nec/evaluator/retrieval_index.h"

#include "nec/motion/byte_io.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/hash.h"
#include "nec/text/caption_text.h"
#include "nec/text/text_encoder.h"
#include "nec/train/checkpoint_io.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <numeric>

namespace nec::evaluator {
namespace {

namespace fs = std::filesystem;

constexpr char kMagic[8] = {'N', 'E', 'C', 'R', 'I', 'D', 'X', '\0'};

std::vector<float> tensor_values(const at::Tensor& embeddings) {
  const at::Tensor values = embeddings.detach().to(torch::kCPU, torch::kFloat32).contiguous();
  return std::vector<float>(values.data_ptr<float>(), values.data_ptr<float>() + values.numel());
}

const float* query_values(const at::Tensor& query, int dim, at::Tensor& holder) {
  holder = query.detach().to(torch::kCPU, torch::kFloat32).reshape({-1}).contiguous();
  if (holder.numel() != dim) {
    throw std::invalid_argument("retrieval query of width " + std::to_string(holder.numel()) + ", the index holds " +
                                std::to_string(dim));
  }
  return holder.data_ptr<float>();
}

// Each row's dot product with the query: rows (count, dim) against (dim), in one matrix-vector product.
std::vector<float> row_dots(const std::vector<float>& rows, int dim, const float* query) {
  const int64_t count = dim > 0 ? static_cast<int64_t>(rows.size()) / dim : 0;
  std::vector<float> dots(static_cast<size_t>(count));
  if (count == 0) return dots;
  const at::Tensor matrix = torch::from_blob(const_cast<float*>(rows.data()), {count, dim}, torch::kFloat32);
  const at::Tensor vector = torch::from_blob(const_cast<float*>(query), {dim}, torch::kFloat32);
  torch::from_blob(dots.data(), {count}, torch::kFloat32).copy_(matrix.mv(vector));
  return dots;
}

// Every row `keep` accepts with its cosine to the query.
std::vector<Match> scored_rows(const at::Tensor& query, const std::vector<float>& rows, int dim,
                               const std::function<bool(int)>& keep) {
  at::Tensor holder;
  const std::vector<float> dots = row_dots(rows, dim, query_values(query, dim, holder));
  std::vector<Match> scored;
  scored.reserve(dots.size());
  for (size_t r = 0; r < dots.size(); ++r) {
    if (!keep || keep(static_cast<int>(r))) scored.push_back({static_cast<int>(r), dots[r]});
  }
  return scored;
}

std::vector<Match> best_of(std::vector<Match> scored, int k) {
  const size_t top = std::min(scored.size(), static_cast<size_t>(std::max(k, 0)));
  std::partial_sort(scored.begin(), scored.begin() + static_cast<std::ptrdiff_t>(top), scored.end(),
                    [](const Match& a, const Match& b) { return a.score > b.score || (a.score == b.score && a.row < b.row); });
  scored.resize(top);
  return scored;
}

// (x - mean) / deviation of the values at `rows` of `values`, in place (0 where they do not spread).
void standardize(std::vector<float>& values, const std::vector<size_t>& rows) {
  if (rows.empty()) return;
  double sum = 0.0, squares = 0.0;
  for (const size_t r : rows) sum += values[r];
  const double mean = sum / static_cast<double>(rows.size());
  for (const size_t r : rows) squares += (values[r] - mean) * (values[r] - mean);
  const double deviation = std::sqrt(squares / static_cast<double>(rows.size()));
  for (const size_t r : rows) values[r] = deviation > 1e-12 ? static_cast<float>((values[r] - mean) / deviation) : 0.f;
}

}  // namespace

std::vector<Match> RetrievalIndex::nearest_clips(const at::Tensor& query, int k,
                                                 const std::function<bool(int clip)>& keep,
                                                 const CaptionBlend& blend) const {
  std::function<bool(int)> keep_row;
  if (keep) keep_row = [&](int row) { return keep(clips[static_cast<size_t>(row)]); };
  std::vector<Match> scored = scored_rows(query, clip_embeddings, dim, keep_row);
  if (blend.weight <= 0.f) return best_of(std::move(scored), k);
  if (blend.weight > 1.f) throw std::invalid_argument("the captions' weight must be in [0, 1]");
  if (clip_captions.size() != clips.size()) throw std::invalid_argument("the retrieval index has no clip captions");
  at::Tensor holder;
  const std::vector<float> caption_scores = row_dots(caption_texts, text_dim, query_values(blend.text, text_dim, holder));
  std::vector<float> motion(scored.size()), text(scored.size());
  std::vector<size_t> all(scored.size()), captioned;
  std::iota(all.begin(), all.end(), size_t{0});
  for (size_t i = 0; i < scored.size(); ++i) {
    motion[i] = scored[i].score;
    const std::vector<int>& rows = clip_captions[static_cast<size_t>(scored[i].row)];
    if (rows.empty()) continue;
    text[i] = -2.f;
    for (const int row : rows) text[i] = std::max(text[i], caption_scores[static_cast<size_t>(row)]);
    captioned.push_back(i);
  }
  standardize(motion, all);
  standardize(text, captioned);
  for (size_t i = 0; i < scored.size(); ++i) {
    const bool has_captions = !clip_captions[static_cast<size_t>(scored[i].row)].empty();
    const float caption_part = has_captions ? text[i] : motion[i];  // a clip without captions: its motion alone
    scored[i].score = (1.f - blend.weight) * motion[i] + blend.weight * caption_part;
  }
  return best_of(std::move(scored), k);
}

std::vector<Match> RetrievalIndex::nearest_captions(const at::Tensor& query, int k) const {
  return best_of(scored_rows(query, caption_embeddings, dim, {}), k);
}

at::Tensor caption_text_vectors(const std::vector<std::string>& captions, const std::string& where) {
  const text::SentenceEncoder encoder = text::shared_sentence_encoder();
  constexpr size_t kChunk = 64;
  std::vector<at::Tensor> chunks;
  for (size_t start = 0; start < captions.size(); start += kChunk) {
    std::vector<std::string> chunk;
    for (size_t i = start; i < std::min(captions.size(), start + kChunk); ++i) {
      chunk.push_back(text::checked_caption(captions[i], captions.size() > 1 ? where + " " + std::to_string(i + 1) : where));
    }
    chunks.push_back(encoder->encode(chunk).sentence);
  }
  if (chunks.empty()) return torch::zeros({0, encoder->dim()});
  return torch::cat(chunks);
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
  std::map<std::string, int> row_of;
  for (const CacheClip& clip : cache.clips) {
    std::vector<int>& rows = index.clip_captions.emplace_back();
    for (const std::string& caption : clip.captions) {
      const auto [it, added] = row_of.emplace(caption, static_cast<int>(index.captions.size()));
      if (added) index.captions.push_back(caption);
      rows.push_back(it->second);
    }
  }
  index.caption_embeddings = tensor_values(session.embed_captions(index.captions, "cache captions"));
  const at::Tensor texts = caption_text_vectors(index.captions, "cache caption");
  index.text_dim = static_cast<int>(texts.size(1));
  index.caption_texts = tensor_values(texts);
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
  append_value(out, static_cast<uint32_t>(index.text_dim));
  append_values(out, index.caption_texts);
  for (const std::vector<int>& rows : index.clip_captions) {
    append_value(out, static_cast<uint32_t>(rows.size()));
    for (const int row : rows) append_value(out, static_cast<uint32_t>(row));
  }
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
  index.text_dim = static_cast<int>(in.get<uint32_t>());
  if (index.text_dim > 1 << 16) throw InputError(path, 0, "the retrieval index is damaged; it will be rebuilt");
  index.caption_texts = in.values<float>(captions * static_cast<uint64_t>(index.text_dim));
  for (uint64_t i = 0; i < clips; ++i) {
    const uint32_t count = in.get<uint32_t>();
    if (count > captions) throw InputError(path, 0, "the retrieval index is damaged; it will be rebuilt");
    std::vector<int>& rows = index.clip_captions.emplace_back();
    for (uint32_t c = 0; c < count; ++c) {
      const uint32_t row = in.get<uint32_t>();
      if (row >= captions) throw InputError(path, 0, "the retrieval index is damaged; it will be rebuilt");
      rows.push_back(static_cast<int>(row));
    }
  }
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

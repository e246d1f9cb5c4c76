// The text encoder: a backbone's reading of the caption -> transformer -> sentence vector.
#include "nec/text/text_encoder.h"

#include "nec/layers/transformer.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/text/caption_text.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"

#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <unordered_map>

namespace nec::text {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("TextEncoderConfig: " + message);
}


int64_t piece_width(const TextEncoderConfig& c) { return c.word_dim > 0 ? c.word_dim : c.dim; }

bool reads_pieces(const TextEncoderConfig& c) { return c.backbone == kPiecesBackbone; }
// Whether the transformer reads a token per piece (max_pieces bounds the caption), or only the sentence vector.
bool reads_each_piece(const TextEncoderConfig& c) { return reads_pieces(c) || c.layers > 0 || c.piece_memory; }

constexpr const char* kPieceFile = "pieces.model";

// InputError for a caption of more than config.max_pieces pieces.
void check_piece_count(int64_t count, const TextEncoderConfig& config, const std::string& where,
                       const std::string& caption) {
  if (reads_each_piece(config) && count > config.max_pieces) {
    throw InputError(where, 0,
                     "the caption has " + std::to_string(count) + " pieces, more than the " +
                         std::to_string(config.max_pieces) + " the text encoder takes: '" + caption + "'");
  }
}

// `where`, with the caption's position when there are several.
std::string caption_name(const std::string& where, size_t index, size_t count) {
  return count > 1 ? where + " (caption " + std::to_string(index + 1) + ")" : where;
}

}  // namespace

void TextEncoderConfig::validate() const {
  require(backbone == kPiecesBackbone || backbone == kUseLiteBackbone,
          "backbone '" + backbone + "' is neither '" + kPiecesBackbone + "' nor '" + kUseLiteBackbone + "'");
  require(reads_pieces(*this) || word_dim == 0, "word_dim must be 0 with the use-lite backbone (it reads no word vectors)");
  require(vocab_size >= 3, "vocab_size must be >= 3 (pad, unknown and a piece)");
  require(word_dim >= 0, "word_dim must be >= 0");
  require(dim >= 1 && heads >= 1 && dim % heads == 0, "heads must divide dim");
  require(layers >= (reads_pieces(*this) ? 1 : 0), "layers must be >= 1 (>= 0 with the use-lite backbone)");
  require(feedforward >= 1 && output_dim >= 1, "feedforward and output_dim must be >= 1");
  require(max_pieces >= 1, "max_pieces must be >= 1");
  require(dropout >= 0 && dropout < 1, "dropout must be in [0, 1)");
  require(piece_dropout >= 0 && piece_dropout < 1, "piece_dropout must be in [0, 1)");
  require(!piece_memory || (!reads_pieces(*this) && layers == 0), "piece_memory needs the use-lite backbone and 0 layers");
}

void visit_fields(train::ConfigVisitor& v, TextEncoderConfig& c) {
  v.added_field("backbone", c.backbone,
                "what reads the caption: \"use-lite\" (the pretrained sentence encoder, frozen) or \"pieces\" "
                "(the piece model and word vectors, trained with the model)");
  v.field("vocab_size", c.vocab_size, "pieces of the piece model (set from --pieces)");
  v.field("word_dim", c.word_dim, "width of the word vectors (set from --glove); 0 = no word channel");
  v.field("dim", c.dim, "token width");
  v.field("layers", c.layers, "transformer layers (use-lite: 0 reads the sentence vector alone)");
  v.field("heads", c.heads, "attention heads; must divide dim");
  v.field("feedforward", c.feedforward, "FFN hidden width");
  v.field("max_pieces", c.max_pieces, "longest caption in pieces; longer ones are refused");
  v.field("output_dim", c.output_dim, "width of the sentence vector");
  v.field("dropout", c.dropout, "transformer dropout in training");
  v.field("piece_dropout", c.piece_dropout,
          "chance a piece id is read as unknown in training, so that the word vectors are read too");
  v.added_field("read_split_words_by_vector", c.read_split_words_by_vector,
          "a word with a vector that the piece model cuts into several pieces is read from its vector alone");
  v.added_field("piece_memory", c.piece_memory,
                "use-lite, 0 layers: each piece's encoder features through one linear map are the per-piece features");
}

TextBatch TextBatch::to(const c10::Device& device) const {
  const auto moved = [&](const at::Tensor& t) { return t.defined() ? t.to(device) : t; };
  return {moved(ids), moved(word_vectors), moved(word_known), moved(encoder_features), moved(encoder_sentence),
          moved(mask)};
}

TextBatch make_text_batch(const std::vector<std::string>& captions, const PieceModel& pieces,
                          const WordVectors* vectors, const TextEncoderConfig& config, const std::string& where) {
  if (config.word_dim > 0 && (vectors == nullptr || vectors->dim() != config.word_dim)) {
    throw std::invalid_argument("make_text_batch: the encoder reads word vectors of width " +
                                std::to_string(config.word_dim) +
                                (vectors ? ", given " + std::to_string(vectors->dim()) : ", given none"));
  }
  std::vector<CaptionPieces> split;
  split.reserve(captions.size());
  int64_t longest = 1;
  for (size_t i = 0; i < captions.size(); ++i) {
    const std::string name = caption_name(where, i, captions.size());
    split.push_back(pieces.split(checked_caption(captions[i], name)));
    const int64_t count = static_cast<int64_t>(split.back().ids.size());
    check_piece_count(count, config, name, captions[i]);
    longest = std::max(longest, count);
  }
  const int64_t b = static_cast<int64_t>(captions.size()), width = config.word_dim;
  TextBatch batch;
  batch.ids = torch::full({b, longest}, kPadPiece, torch::kInt64);
  batch.word_vectors = torch::zeros({b, longest, width});
  batch.word_known = torch::zeros({b, longest, 1});
  batch.mask = torch::zeros({b, longest}, torch::kBool);
  auto ids = batch.ids.accessor<int64_t, 2>();
  auto known = batch.word_known.accessor<float, 3>();
  auto mask = batch.mask.accessor<bool, 2>();
  float* word_data = batch.word_vectors.data_ptr<float>();
  for (int64_t i = 0; i < b; ++i) {
    const CaptionPieces& caption = split[static_cast<size_t>(i)];
    std::vector<int> pieces_of_word(caption.words.size(), 0);  // counted only for read_split_words_by_vector
    if (config.read_split_words_by_vector) {
      for (const int w : caption.word_of_piece) ++pieces_of_word[static_cast<size_t>(w)];
    }
    for (size_t p = 0; p < caption.ids.size(); ++p) {
      ids[i][static_cast<int64_t>(p)] = caption.ids[p];
      mask[i][static_cast<int64_t>(p)] = true;
      if (width == 0) continue;
      const size_t w = static_cast<size_t>(caption.word_of_piece[p]);
      const std::optional<size_t> word = vectors->index_of(caption.words[w]);
      if (!word) continue;
      std::copy_n(vectors->vector_data(*word), width, word_data + (i * longest + static_cast<int64_t>(p)) * width);
      known[i][static_cast<int64_t>(p)][0] = 1.0f;
      if (config.read_split_words_by_vector && pieces_of_word[w] > 1) ids[i][static_cast<int64_t>(p)] = kUnknownPiece;
    }
  }
  return batch;
}

namespace {

// Each caption's pieces as the sentence encoder reads them; InputError as make_text_batch.
std::vector<std::vector<int>> sentence_pieces(const std::vector<std::string>& captions, const SentenceEncoderImpl& encoder,
                                              const TextEncoderConfig& config, const std::string& where) {
  if (encoder.dim() != kUseLiteWidth) {
    throw std::invalid_argument("make_sentence_batch: the sentence encoder is " + std::to_string(encoder.dim()) +
                                " wide, the text encoder reads " + std::to_string(kUseLiteWidth));
  }
  std::vector<std::vector<int>> pieces;
  pieces.reserve(captions.size());
  for (size_t i = 0; i < captions.size(); ++i) {
    const std::string name = caption_name(where, i, captions.size());
    pieces.push_back(encoder.pieces().encode(checked_caption(captions[i], name)));
    check_piece_count(static_cast<int64_t>(pieces.back().size()), config, name, captions[i]);
  }
  return pieces;
}

TextBatch to_text_batch(const SentenceEncoding& encoded) {
  TextBatch batch;
  batch.encoder_features = encoded.features;
  batch.encoder_sentence = encoded.sentence;
  batch.mask = encoded.mask;
  return batch;
}

}  // namespace

TextBatch make_sentence_batch(const std::vector<std::string>& captions, const SentenceEncoderImpl& encoder,
                              const TextEncoderConfig& config, const std::string& where) {
  return to_text_batch(encoder.encode_pieces(sentence_pieces(captions, encoder, config, where)));
}

// The sentence encoder's outputs for a fixed set of captions, keyed by their pieces.
class RememberedEncodings {
 public:
  // Encodes `pieces` (rows of captions, repeats allowed) 64 rows at a time and keeps each row's
  // encoding while max_bytes allows.
  RememberedEncodings(const std::vector<std::vector<int>>& pieces, const SentenceEncoderImpl& encoder, size_t max_bytes) {
    constexpr size_t kChunk = 64;
    std::vector<std::vector<int>> chunk;
    std::vector<std::string> chunk_keys;
    size_t bytes = 0;
    const auto encode_chunk = [&] {
      const SentenceEncoding encoded = encoder.encode_pieces(chunk);
      for (size_t i = 0; i < chunk.size(); ++i) {
        Encoding row = row_of(encoded, static_cast<int64_t>(i));
        const size_t row_bytes = static_cast<size_t>(row.features.numel() + row.sentence.numel()) * sizeof(float);
        if (bytes + row_bytes > max_bytes) return false;
        bytes += row_bytes;
        encodings_.emplace(chunk_keys[i], std::move(row));
      }
      chunk.clear();
      chunk_keys.clear();
      return true;
    };
    for (const std::vector<int>& row : pieces) {
      std::string key = key_of(row);
      if (encodings_.count(key) > 0 || std::find(chunk_keys.begin(), chunk_keys.end(), key) != chunk_keys.end()) continue;
      chunk.push_back(row);
      chunk_keys.push_back(std::move(key));
      if (chunk.size() == kChunk && !encode_chunk()) return;
    }
    if (!chunk.empty()) encode_chunk();
  }

  size_t size() const { return encodings_.size(); }

  // The batch of these captions: kept rows as kept, the others encoded together.
  TextBatch read(const std::vector<std::vector<int>>& pieces, const SentenceEncoderImpl& encoder) const {
    std::vector<const Encoding*> rows(pieces.size(), nullptr);
    std::vector<std::vector<int>> missing;
    std::vector<size_t> missing_rows;
    for (size_t i = 0; i < pieces.size(); ++i) {
      const auto kept = encodings_.find(key_of(pieces[i]));
      if (kept != encodings_.end()) {
        rows[i] = &kept->second;
      } else {
        missing.push_back(pieces[i]);
        missing_rows.push_back(i);
      }
    }
    if (missing.size() == pieces.size()) return to_text_batch(encoder.encode_pieces(missing));
    std::vector<Encoding> fresh;
    if (!missing.empty()) {
      const SentenceEncoding encoded = encoder.encode_pieces(missing);
      for (size_t m = 0; m < missing.size(); ++m) fresh.push_back(row_of(encoded, static_cast<int64_t>(m)));
      for (size_t m = 0; m < missing.size(); ++m) rows[missing_rows[m]] = &fresh[m];
    }
    int64_t longest = 0;
    for (const Encoding* row : rows) longest = std::max(longest, row->features.size(0));
    const int64_t batch = static_cast<int64_t>(rows.size());
    const at::Tensor& first = rows.front()->sentence;
    TextBatch out;
    out.encoder_features = torch::zeros({batch, longest, first.size(0)}, first.options());
    out.mask = torch::zeros({batch, longest}, first.options().dtype(torch::kBool));
    std::vector<at::Tensor> sentences;
    for (int64_t b = 0; b < batch; ++b) {
      const Encoding& row = *rows[static_cast<size_t>(b)];
      const int64_t length = row.features.size(0);
      out.encoder_features[b].narrow(0, 0, length).copy_(row.features);
      out.mask[b].narrow(0, 0, length).fill_(true);
      sentences.push_back(row.sentence);
    }
    out.encoder_sentence = torch::stack(sentences);
    return out;
  }

 private:
  struct Encoding {
    at::Tensor features;  // (pieces, width)
    at::Tensor sentence;  // (width)
  };

  static std::string key_of(const std::vector<int>& pieces) {
    return {reinterpret_cast<const char*>(pieces.data()), pieces.size() * sizeof(int)};
  }
  // Row `i` of `encoded` without its padding.
  static Encoding row_of(const SentenceEncoding& encoded, int64_t i) {
    const int64_t length = encoded.mask[i].sum().item<int64_t>();
    return {encoded.features[i].narrow(0, 0, length).clone(), encoded.sentence[i].clone()};
  }

  std::unordered_map<std::string, Encoding> encodings_;
};

SentenceEncoder shared_sentence_encoder() {
  static std::mutex mutex;
  static SentenceEncoder shared{nullptr};
  const std::lock_guard<std::mutex> lock(mutex);
  if (shared.is_empty()) shared = SentenceEncoder(default_sentence_encoder_dir());
  return shared;
}

CaptionReader CaptionReader::for_training(TextEncoderConfig& config, const std::string& piece_model_path) {
  CaptionReader reader;
  if (reads_pieces(config)) {
    if (piece_model_path.empty()) {
      throw InputError("the text encoder reads pieces: give the piece model (`nec text train-tokenizer` makes one), "
                       "or set model.text.backbone to \"use-lite\"");
    }
    reader.pieces_ = std::make_shared<const PieceModel>(PieceModel::load(piece_model_path));
    reader.piece_model_path_ = piece_model_path;
    reader.piece_model_bytes_ = read_file(piece_model_path, size_t{1} << 26);
    config.vocab_size = reader.pieces_->vocab_size();
  } else {
    reader.sentence_encoder_ = shared_sentence_encoder();
  }
  reader.config_ = config;
  return reader;
}

int64_t CaptionReader::count_pieces(const std::string& caption) const {
  return pieces_ ? static_cast<int64_t>(pieces_->split(caption).ids.size())
                 : static_cast<int64_t>(sentence_encoder_->pieces().encode(caption).size());
}

TextBatch CaptionReader::read(const std::vector<std::string>& captions, const WordVectors* vectors,
                              const std::string& where) const {
  if (pieces_) return make_text_batch(captions, *pieces_, vectors, config_, where);
  if (sentence_encoder_.is_empty()) throw std::logic_error("CaptionReader::read on a reader that reads nothing");
  if (!remembered_) return make_sentence_batch(captions, *sentence_encoder_, config_, where);
  return remembered_->read(sentence_pieces(captions, *sentence_encoder_, config_, where), *sentence_encoder_);
}

void CaptionReader::remember_corpus_encodings(const DatasetCache& cache, size_t max_bytes) {
  if (sentence_encoder_.is_empty()) return;
  std::vector<std::vector<int>> pieces;
  for (const CacheClip& clip : cache.clips) {
    if (clip.split == Split::Test) continue;
    for (const std::string& caption : clip.captions) {
      pieces.push_back(sentence_encoder_->pieces().encode(checked_caption(caption, "clip " + clip.id)));
    }
  }
  remembered_ = std::make_shared<const RememberedEncodings>(pieces, *sentence_encoder_, max_bytes);
}

size_t CaptionReader::remembered_captions() const { return remembered_ ? remembered_->size() : 0; }

void CaptionReader::check_corpus(const DatasetCache& cache, const std::string& data_name) const {
  for (const CacheClip& clip : cache.clips) {
    if (clip.split == Split::Test) continue;
    for (const std::string& caption : clip.captions) {
      const int64_t count = count_pieces(checked_caption(caption, data_name + ": clip " + clip.id));
      if (reads_each_piece(config_) && count > config_.max_pieces) {
        throw InputError(data_name, 0, "clip " + clip.id + " has a caption of " + std::to_string(count) +
                                           " pieces, more than model.text.max_pieces = " +
                                           std::to_string(config_.max_pieces) + " (raise it in the config): '" +
                                           caption + "'");
      }
    }
  }
}

void save_checkpoint_captions(const std::string& dir, const CaptionReader& captions, nlohmann::json& config) {
  if (captions.pieces() == nullptr) return;
  write_file_atomic((std::filesystem::path(dir) / kPieceFile).string(), captions.piece_model_bytes());
  config["pieces"] = kPieceFile;
}

CaptionReader load_checkpoint_captions(const std::string& dir, const nlohmann::json& root,
                                       const TextEncoderConfig& config, const train::JsonFields& fields) {
  CaptionReader reader;
  reader.config_ = config;
  if (!reads_pieces(config)) {
    reader.sentence_encoder_ = shared_sentence_encoder();
    return reader;
  }
  reader.piece_model_path_ = (std::filesystem::path(dir) / fields.entry(root, "pieces")).string();
  reader.pieces_ = std::make_shared<const PieceModel>(PieceModel::load(reader.piece_model_path_));
  if (reader.pieces_->vocab_size() != config.vocab_size) {
    fields.fail("the piece model has " + std::to_string(reader.pieces_->vocab_size()) + " pieces, the text encoder " +
                std::to_string(config.vocab_size) + "; " + fields.hint());
  }
  reader.piece_model_bytes_ = read_file(reader.piece_model_path_, size_t{1} << 26);
  return reader;
}

TextEncoderImpl::TextEncoderImpl(const TextEncoderConfig& config) : config_(config) {
  config_.validate();
  if (reads_pieces(config_)) {
    piece_embedding_ = register_module("piece_embedding", torch::nn::Embedding(config_.vocab_size, piece_width(config_)));
    input_ = register_module("input", torch::nn::Linear(piece_width(config_) + config_.word_dim + 1, config_.dim));
  } else {
    input_ = register_module("input", torch::nn::Linear(kUseLiteWidth, config_.dim));
    if (config_.layers > 0) {
      encoder_sentence_ = register_module("encoder_sentence", torch::nn::Linear(kUseLiteWidth, config_.output_dim));
    }
    if (config_.piece_memory) piece_map_ = register_module("piece_map", torch::nn::Linear(kUseLiteWidth, config_.dim));
  }
  if (config_.layers > 0) {
    positions_ = register_parameter("positions", torch::randn({config_.max_pieces, config_.dim}) * 0.02);
    const layers::TransformerOptions layer{config_.dim, config_.heads, config_.feedforward, config_.dropout};
    transformer_ = register_module("transformer", std::make_shared<layers::TransformerStackImpl>(layer, config_.layers));
  }
  sentence_ = register_module("sentence", torch::nn::Linear(config_.dim, config_.output_dim));
}

int64_t TextEncoderImpl::init_piece_embeddings(const PieceModel& pieces, const WordVectors& vectors) {
  if (!reads_pieces(config_)) throw std::invalid_argument("init_piece_embeddings: the encoder reads no pieces");
  if (config_.word_dim != vectors.dim()) {
    throw std::invalid_argument("init_piece_embeddings: word vectors of width " + std::to_string(vectors.dim()) +
                                ", the encoder reads " + std::to_string(config_.word_dim));
  }
  torch::NoGradGuard no_grad;
  at::Tensor weight = piece_embedding_->weight;
  int64_t initialised = 0;
  const int64_t count = std::min<int64_t>(pieces.vocab_size(), config_.vocab_size);
  for (int64_t id = 0; id < count; ++id) {
    if (!pieces.starts_word(static_cast<int>(id))) continue;
    const std::optional<size_t> word = vectors.index_of(pieces.piece_text(static_cast<int>(id)));
    if (!word) continue;
    weight[id].copy_(torch::from_blob(const_cast<float*>(vectors.vector_data(*word)), {config_.word_dim}, torch::kFloat32));
    ++initialised;
  }
  return initialised;
}

at::Tensor TextEncoderImpl::dropped_encoder_features(const TextBatch& batch) {
  const at::Tensor& features = batch.encoder_features;
  if (!is_training() || config_.piece_dropout == 0) return features;
  const at::Tensor kept = torch::rand({features.size(0), features.size(1), 1}, features.options()) >= config_.piece_dropout;
  return features * kept.to(features.scalar_type());
}

at::Tensor TextEncoderImpl::input_tokens(const TextBatch& batch) {
  if (!reads_pieces(config_)) return input_(dropped_encoder_features(batch));
  const bool dropping = is_training() && config_.piece_dropout > 0;
  at::Tensor ids = batch.ids;
  if (dropping) {
    const at::Tensor dropped = torch::rand(ids.sizes(), torch::TensorOptions().device(ids.device())) < config_.piece_dropout;
    ids = torch::where(dropped.logical_and(batch.mask), torch::full_like(ids, kUnknownPiece), ids);
  }
  std::vector<at::Tensor> channels{piece_embedding_(ids)};
  if (config_.word_dim > 0) channels.push_back(batch.word_vectors);
  channels.push_back(batch.word_known);
  return input_(torch::cat(channels, -1));
}

TextEncoding TextEncoderImpl::forward(const TextBatch& batch) {
  TextEncoding out;
  if (config_.layers == 0) {  // use-lite with no layers: the sentence vector through one hidden layer
    const at::Tensor hidden =
        torch::gelu(input_(torch::dropout(batch.encoder_sentence, config_.dropout, is_training())));
    out.sentence = sentence_(hidden);
    if (config_.piece_memory) {
      out.features = piece_map_(dropped_encoder_features(batch));
      out.mask = batch.mask;
    } else {
      out.features = hidden.unsqueeze(1);
      out.mask = torch::ones({hidden.size(0), 1}, hidden.options().dtype(torch::kBool));
    }
    return out;
  }
  const int64_t pieces = batch.mask.size(1);
  if (pieces > config_.max_pieces) {
    throw std::invalid_argument("TextEncoder: " + std::to_string(pieces) + " pieces, at most " +
                                std::to_string(config_.max_pieces));
  }
  const at::Tensor tokens = input_tokens(batch) + positions_.narrow(0, 0, pieces).unsqueeze(0);
  out.mask = batch.mask;
  out.features = transformer_->forward(tokens, layers::padding_bias(batch.mask));
  out.sentence = sentence_(layers::masked_mean(out.features, batch.mask));
  if (!reads_pieces(config_)) out.sentence = out.sentence + encoder_sentence_(batch.encoder_sentence);
  return out;
}

}  // namespace nec::text

// The text encoder: pieces + word vectors -> transformer -> sentence vector.
#include "nec/text/text_encoder.h"

#include "nec/layers/transformer.h"
#include "nec/motion/error.h"
#include "nec/text/caption_text.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"

#include <torch/torch.h>

#include <stdexcept>

namespace nec::text {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw std::invalid_argument("TextEncoderConfig: " + message);
}


int64_t piece_width(const TextEncoderConfig& c) { return c.word_dim > 0 ? c.word_dim : c.dim; }

}  // namespace

void TextEncoderConfig::validate() const {
  require(vocab_size >= 3, "vocab_size must be >= 3 (pad, unknown and a piece)");
  require(word_dim >= 0, "word_dim must be >= 0");
  require(dim >= 1 && heads >= 1 && dim % heads == 0, "heads must divide dim");
  require(layers >= 1 && feedforward >= 1 && output_dim >= 1, "layers, feedforward and output_dim must be >= 1");
  require(max_pieces >= 1, "max_pieces must be >= 1");
  require(dropout >= 0 && dropout < 1, "dropout must be in [0, 1)");
  require(piece_dropout >= 0 && piece_dropout < 1, "piece_dropout must be in [0, 1)");
}

void visit_fields(train::ConfigVisitor& v, TextEncoderConfig& c) {
  v.field("vocab_size", c.vocab_size, "pieces of the piece model (set from --pieces)");
  v.field("word_dim", c.word_dim, "width of the word vectors (set from --glove); 0 = no word channel");
  v.field("dim", c.dim, "token width");
  v.field("layers", c.layers, "transformer layers");
  v.field("heads", c.heads, "attention heads; must divide dim");
  v.field("feedforward", c.feedforward, "FFN hidden width");
  v.field("max_pieces", c.max_pieces, "longest caption in pieces; longer ones are refused");
  v.field("output_dim", c.output_dim, "width of the sentence vector");
  v.field("dropout", c.dropout, "transformer dropout in training");
  v.field("piece_dropout", c.piece_dropout,
          "chance a piece id is read as unknown in training, so that the word vectors are read too");
  v.added_field("read_split_words_by_vector", c.read_split_words_by_vector,
          "a word with a vector that the piece model cuts into several pieces is read from its vector alone");
}

PieceModel load_checkpoint_pieces(const std::string& path, const TextEncoderConfig& config,
                                  const train::JsonFields& fields) {
  PieceModel pieces = PieceModel::load(path);
  if (pieces.vocab_size() != config.vocab_size) {
    fields.fail("the piece model has " + std::to_string(pieces.vocab_size()) + " pieces, the text encoder " +
                std::to_string(config.vocab_size) + "; " + fields.hint());
  }
  return pieces;
}

TextBatch TextBatch::to(const c10::Device& device) const {
  return {ids.to(device), word_vectors.to(device), word_known.to(device), mask.to(device)};
}

void check_corpus_captions(const DatasetCache& cache, const PieceModel& pieces, const TextEncoderConfig& config,
                           const std::string& data_name) {
  for (const CacheClip& clip : cache.clips) {
    if (clip.split == Split::Test) continue;
    for (const std::string& caption : clip.captions) {
      const size_t count = pieces.split(checked_caption(caption, data_name + ": clip " + clip.id)).ids.size();
      if (static_cast<int64_t>(count) > config.max_pieces) {
        throw InputError(data_name, 0, "clip " + clip.id + " has a caption of " + std::to_string(count) +
                                           " pieces, more than model.text.max_pieces = " +
                                           std::to_string(config.max_pieces) + " (raise it in the config): '" +
                                           caption + "'");
      }
    }
  }
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
    const std::string name = captions.size() > 1 ? where + " (caption " + std::to_string(i + 1) + ")" : where;
    split.push_back(pieces.split(checked_caption(captions[i], name)));
    const int64_t count = static_cast<int64_t>(split.back().ids.size());
    if (count > config.max_pieces) {
      throw InputError(name, 0,
                       "the caption has " + std::to_string(count) + " pieces, more than the " +
                           std::to_string(config.max_pieces) + " the text encoder takes: '" + captions[i] + "'");
    }
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

TextEncoderImpl::TextEncoderImpl(const TextEncoderConfig& config) : config_(config) {
  config_.validate();
  piece_embedding_ = register_module("piece_embedding", torch::nn::Embedding(config_.vocab_size, piece_width(config_)));
  input_ = register_module("input", torch::nn::Linear(piece_width(config_) + config_.word_dim + 1, config_.dim));
  positions_ = register_parameter("positions", torch::randn({config_.max_pieces, config_.dim}) * 0.02);
  const layers::TransformerOptions layer{config_.dim, config_.heads, config_.feedforward, config_.dropout};
  transformer_ = register_module("transformer", std::make_shared<layers::TransformerStackImpl>(layer, config_.layers));
  sentence_ = register_module("sentence", torch::nn::Linear(config_.dim, config_.output_dim));
}

int64_t TextEncoderImpl::init_piece_embeddings(const PieceModel& pieces, const WordVectors& vectors) {
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

TextEncoding TextEncoderImpl::forward(const TextBatch& batch) {
  const int64_t pieces = batch.ids.size(1);
  if (pieces > config_.max_pieces) {
    throw std::invalid_argument("TextEncoder: " + std::to_string(pieces) + " pieces, at most " +
                                std::to_string(config_.max_pieces));
  }
  at::Tensor ids = batch.ids;
  if (is_training() && config_.piece_dropout > 0) {
    const at::Tensor dropped = torch::rand(ids.sizes(), torch::TensorOptions().device(ids.device())) < config_.piece_dropout;
    ids = torch::where(dropped.logical_and(batch.mask), torch::full_like(ids, kUnknownPiece), ids);
  }
  std::vector<at::Tensor> channels{piece_embedding_(ids)};
  if (config_.word_dim > 0) channels.push_back(batch.word_vectors);
  channels.push_back(batch.word_known);
  const at::Tensor tokens = input_(torch::cat(channels, -1)) + positions_.narrow(0, 0, pieces).unsqueeze(0);
  TextEncoding out;
  out.mask = batch.mask;
  out.features = transformer_->forward(tokens, layers::padding_bias(batch.mask));
  out.sentence = sentence_(layers::masked_mean(out.features, batch.mask));
  return out;
}

}  // namespace nec::text

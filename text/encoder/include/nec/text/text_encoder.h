// The text encoder (DESIGN.md, Text) shared by the evaluator, gpt/ and
// diffusion/: caption pieces plus the word vector of the word each piece
// belongs to, a small pre-norm transformer, a pooled sentence vector and
// per-piece features with their mask.
//
//   const PieceModel pieces = PieceModel::load("spm.model");
//   TextEncoderConfig config;  config.vocab_size = pieces.vocab_size();  config.word_dim = vectors.dim();
//   TextEncoder encoder(config);
//   encoder->init_piece_embeddings(pieces, vectors);        // whole-word pieces start at their GloVe vector
//   TextBatch batch = make_text_batch({"a dog trots forward"}, pieces, &vectors, config, "query");
//   TextEncoding out = encoder->forward(batch);
//   // out.sentence (B, output_dim), out.features (B, P, dim), out.mask (B, P)
//
// Why the word channel: a word no training caption used ("hound",
// "scuttles") is cut into pieces the encoder never learnt, but its GloVe
// vector sits near the words it did learn ("dog", "crawls"), and every piece
// of the word carries it. In training, piece ids are replaced by the unknown
// piece with probability piece_dropout so that the encoder learns to read
// the word channel and not only the ids; with read_split_words_by_vector a
// word the piece model does not know whole is read that way always.
#pragma once

#include "nec/corpus/dataset.h"
#include "nec/text/piece_model.h"
#include "nec/text/word_vectors.h"

#include <ATen/core/Tensor.h>
#include <c10/core/Device.h>
#include <torch/nn/module.h>
#include <torch/nn/modules/embedding.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

#include <cstdint>
#include <string>
#include <vector>

namespace nec::train {
class ConfigVisitor;
class JsonFields;
}
namespace nec::layers {
class TransformerStackImpl;
}

namespace nec::text {

// Hyper-parameters; saved with a model.
struct TextEncoderConfig {
  int64_t vocab_size = 1000;  // pieces of the piece model (set from it), e.g. 1000
  int64_t word_dim = 100;     // width of the word vectors, e.g. 100 (GloVe); 0 = no word channel
  int64_t dim = 128;          // token width D, e.g. 128
  int64_t layers = 2;         // transformer layers, e.g. 2
  int64_t heads = 4;          // attention heads; must divide dim
  int64_t feedforward = 256;  // FFN hidden width, e.g. 2 * dim
  int64_t max_pieces = 48;    // longest caption in pieces; longer ones are refused
  int64_t output_dim = 128;   // width of the sentence vector
  double dropout = 0.1;       // in the transformer, training only
  double piece_dropout = 0.1; // chance a piece id is read as unknown in training (the word channel stays)
  // A word with a vector that the piece model cuts into several pieces (a word
  // the piece model's corpus never used: "flutters" -> "fl" "utter" "s") gets
  // the unknown piece for each of them, so that it is read from its vector
  // alone, as piece dropout trained, and not from pieces learnt for other words.
  bool read_split_words_by_vector = false;

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, TextEncoderConfig& c);  // train/config_fields.h

// The piece model a checkpoint's text encoder reads, from `path`; a piece count other than
// config.vocab_size fails through `fields` (naming the checkpoint's config.json and its hint).
PieceModel load_checkpoint_pieces(const std::string& path, const TextEncoderConfig& config,
                                  const train::JsonFields& fields);

// Captions as tensors, padded to the longest.
struct TextBatch {
  at::Tensor ids;           // (B, P) int64 piece ids, kPadPiece at padding
  at::Tensor word_vectors;  // (B, P, word_dim) float32: the vector of each piece's word; 0 for unknown words, padding
  at::Tensor word_known;    // (B, P, 1) float32: 1 where the word has a vector
  at::Tensor mask;          // (B, P) bool, true for real pieces

  TextBatch to(const c10::Device& device) const;
};

// Normalizes (checked_caption) and splits each caption; `vectors` may be null
// when config.word_dim is 0, else its width must be word_dim. InputError
// naming `where` (and the caption's index when there are several) for an
// empty or letterless caption or one with more than max_pieces pieces.
TextBatch make_text_batch(const std::vector<std::string>& captions, const PieceModel& pieces,
                          const WordVectors* vectors, const TextEncoderConfig& config, const std::string& where);

// Refuses, before training starts rather than at the step that draws it, a
// caption of a train or val clip of `cache` that is empty, has no letter or
// has more than config.max_pieces pieces: InputError naming `data_name`, the
// clip and the caption.
void check_corpus_captions(const DatasetCache& cache, const PieceModel& pieces, const TextEncoderConfig& config,
                           const std::string& data_name);

struct TextEncoding {
  at::Tensor sentence;  // (B, output_dim) pooled sentence vector
  at::Tensor features;  // (B, P, dim) per-piece features (after the final LayerNorm)
  at::Tensor mask;      // (B, P) bool
};

class TextEncoderImpl : public torch::nn::Module {
 public:
  explicit TextEncoderImpl(const TextEncoderConfig& config);
  const TextEncoderConfig& config() const { return config_; }

  // Piece embeddings of the pieces that are whole words of `vectors` ("▁dog"
  // -> the vector of "dog") become those vectors; returns how many did.
  // Needs word_dim == vectors.dim().
  int64_t init_piece_embeddings(const PieceModel& pieces, const WordVectors& vectors);

  TextEncoding forward(const TextBatch& batch);

 private:
  TextEncoderConfig config_;
  torch::nn::Embedding piece_embedding_{nullptr};  // (vocab, word_dim or dim)
  torch::nn::Linear input_{nullptr};               // [piece ‖ word vector ‖ known] -> dim
  at::Tensor positions_;                           // (max_pieces, dim) learnt
  std::shared_ptr<layers::TransformerStackImpl> transformer_;
  torch::nn::Linear sentence_{nullptr};            // dim -> output_dim
};
TORCH_MODULE(TextEncoder);

}  // namespace nec::text

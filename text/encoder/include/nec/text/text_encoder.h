// The text encoder (DESIGN.md, Text) shared by the evaluator, gpt/ and
// diffusion/: what reads the caption (its backbone), a small pre-norm
// transformer, a pooled sentence vector and per-piece features with their mask.
//
//   TextEncoderConfig config;  config.backbone = kUseLiteBackbone;
//   const CaptionReader captions = CaptionReader::for_training(config, /*piece_model_path=*/"");
//   TextEncoder encoder(config);
//   TextEncoding out = encoder->forward(captions.read({"a dog trots forward"}, nullptr, "query"));
//   // out.sentence (B, output_dim), out.features (B, P, dim), out.mask (B, P)
//
// Two backbones. "use-lite": the pretrained sentence encoder
// (text/sentence_encoder.h), frozen, under a small trainable head. Why: words
// no caption of the corpus used ("pup", "greets") land near the words it did,
// as the pretrained encoder learnt from far more English than our captions.
// With layers = 0 the head reads the encoder's sentence vector: one GELU
// hidden layer of width dim (the single "piece" of features, or with
// piece_memory each piece's features through one linear map) and a linear map
// to the sentence vector. With layers > 0 a transformer reads the
// encoder's per-piece features and the sentence vector adds a linear map of
// the encoder's own; trained on template captions it learns the pieces
// themselves and reads new words worse (docs/text.md has the measurements).
// "pieces": the corpus's own piece model and, with word_dim, GloVe word
// vectors, trained from scratch with the model (the models before the
// sentence encoder; checkpoints without a backbone field read pieces).
//
// Why the word channel of "pieces": a word no training caption used ("hound",
// "scuttles") is cut into pieces the encoder never learnt, but its GloVe
// vector sits near the words it did learn ("dog", "crawls"), and every piece
// of the word carries it. In training, piece ids are replaced by the unknown
// piece with probability piece_dropout so that the encoder learns to read
// the word channel and not only the ids; with read_split_words_by_vector a
// word the piece model does not know whole is read that way always.
#pragma once

#include "nec/corpus/dataset.h"
#include "nec/text/piece_model.h"
#include "nec/text/sentence_encoder.h"
#include "nec/text/word_vectors.h"

#include <nlohmann/json_fwd.hpp>

#include <ATen/core/Tensor.h>
#include <c10/core/Device.h>
#include <torch/nn/module.h>
#include <torch/nn/modules/embedding.h>
#include <torch/nn/modules/linear.h>
#include <torch/nn/modules/normalization.h>
#include <torch/nn/pimpl.h>

#include <cstddef>
#include <cstdint>
#include <memory>
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

constexpr const char* kPiecesBackbone = "pieces";
constexpr const char* kUseLiteBackbone = "use-lite";
constexpr int64_t kUseLiteWidth = 512;  // the sentence encoder's feature and sentence width

// Hyper-parameters; saved with a model.
struct TextEncoderConfig {
  std::string backbone = kPiecesBackbone;  // what reads the caption: "pieces" or "use-lite" (see above)
  int64_t vocab_size = 1000;  // pieces: pieces of the piece model (set from it), e.g. 1000
  int64_t word_dim = 100;     // pieces: width of the word vectors, e.g. 100 (GloVe); 0 = no word channel (use-lite: 0)
  int64_t dim = 128;          // token width D, e.g. 128
  int64_t layers = 2;         // transformer layers, e.g. 2; use-lite may have 0 (the sentence vector alone)
  int64_t heads = 4;          // attention heads; must divide dim
  int64_t feedforward = 256;  // FFN hidden width, e.g. 2 * dim
  int64_t max_pieces = 48;    // longest caption in pieces; longer ones are refused (not with use-lite, 0 layers)
  int64_t output_dim = 128;   // width of the sentence vector
  double dropout = 0.1;       // in the transformer, training only
  double piece_dropout = 0.1; // training: pieces, chance a piece id is read as unknown (the word channel stays);
                              // use-lite, chance a piece's features are zeroed (the sentence vector stays)
  // A word with a vector that the piece model cuts into several pieces (a word
  // the piece model's corpus never used: "flutters" -> "fl" "utter" "s") gets
  // the unknown piece for each of them, so that it is read from its vector
  // alone, as piece dropout trained, and not from pieces learnt for other words.
  bool read_split_words_by_vector = false;
  // use-lite, 0 layers: each piece's encoder features through one linear map
  // are the per-piece features, beside the sentence vector's hidden layer (no
  // trained transformer over the pieces, so that a model attending to them
  // reads words the encoder knows and the captions never used).
  bool piece_memory = false;

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};
void visit_fields(train::ConfigVisitor& v, TextEncoderConfig& c);  // train/config_fields.h

// Captions as tensors, padded to the longest. Backbone "pieces" fills ids,
// word_vectors and word_known; "use-lite" fills encoder_features and
// encoder_sentence; both the mask.
struct TextBatch {
  at::Tensor ids;           // (B, P) int64 piece ids, kPadPiece at padding
  at::Tensor word_vectors;  // (B, P, word_dim) float32: the vector of each piece's word; 0 for unknown words, padding
  at::Tensor word_known;    // (B, P, 1) float32: 1 where the word has a vector
  at::Tensor encoder_features;  // (B, P, kUseLiteWidth) the sentence encoder's per-piece features, 0 at padding
  at::Tensor encoder_sentence;  // (B, kUseLiteWidth) its unit sentence vectors
  at::Tensor mask;          // (B, P) bool, true for real pieces

  TextBatch to(const c10::Device& device) const;
};

// Normalizes (checked_caption) and splits each caption; `vectors` may be null
// when config.word_dim is 0, else its width must be word_dim. InputError
// naming `where` (and the caption's index when there are several) for an
// empty or letterless caption or one with more than max_pieces pieces.
TextBatch make_text_batch(const std::vector<std::string>& captions, const PieceModel& pieces,
                          const WordVectors* vectors, const TextEncoderConfig& config, const std::string& where);

// Backbone "use-lite": the frozen sentence encoder's outputs for each
// normalized, checked caption (InputError as make_text_batch).
TextBatch make_sentence_batch(const std::vector<std::string>& captions, const SentenceEncoderImpl& encoder,
                              const TextEncoderConfig& config, const std::string& where);

// The sentence encoder setup fetched (default_sentence_encoder_dir()), loaded
// once per process and shared by every model that reads it.
SentenceEncoder shared_sentence_encoder();

class RememberedEncodings;  // text_encoder.cpp

// How a model's captions become a TextBatch: the piece model of backbone
// "pieces" (with the word vectors the caller gives) or the shared sentence
// encoder of "use-lite". Cheap to copy.
class CaptionReader {
 public:
  CaptionReader() = default;
  // For a model about to be trained: "pieces" reads the piece model at
  // piece_model_path (required) and sets config.vocab_size from it; "use-lite"
  // opens the sentence encoder and ignores the path.
  static CaptionReader for_training(TextEncoderConfig& config, const std::string& piece_model_path);

  const TextEncoderConfig& config() const { return config_; }
  // The piece model (null for use-lite), its file and that file's bytes (saved with checkpoints; empty for use-lite).
  const PieceModel* pieces() const { return pieces_.get(); }
  const std::string& piece_model_path() const { return piece_model_path_; }
  const std::string& piece_model_bytes() const { return piece_model_bytes_; }

  // Pieces of a normalized caption as the backbone cuts it.
  int64_t count_pieces(const std::string& caption) const;
  // make_text_batch or make_sentence_batch; `vectors` as make_text_batch needs them (ignored by use-lite).
  TextBatch read(const std::vector<std::string>& captions, const WordVectors* vectors, const std::string& where) const;
  // For trainers (use-lite; nothing for pieces): encodes the captions of the
  // train and val clips of `cache` once, 64 at a time in the cache's order,
  // and keeps them (as many as max_bytes holds) for this reader and its copies
  // to read from then on; other captions are encoded as they come. Why: the
  // corpus's captions come back every epoch, and encoding them was 6-20 % of a
  // training step. Kept once, before the first step, a caption reads the same
  // at every step and in a resumed run. The numbers differ from encoding a
  // batch afresh by float rounding (products of other shapes).
  void remember_corpus_encodings(const DatasetCache& cache, size_t max_bytes);
  // Captions whose encodings are kept (0 when none are).
  size_t remembered_captions() const;
  // Refuses, before training starts rather than at the step that draws it, a
  // caption of a train or val clip of `cache` that is empty, has no letter or
  // has more than config.max_pieces pieces: InputError naming `data_name`, the
  // clip and the caption.
  void check_corpus(const DatasetCache& cache, const std::string& data_name) const;

 private:
  friend CaptionReader load_checkpoint_captions(const std::string&, const nlohmann::json&, const TextEncoderConfig&,
                                                const train::JsonFields&);
  TextEncoderConfig config_;
  std::shared_ptr<const PieceModel> pieces_;  // shared: a piece model holds a library handle and is not copied
  std::string piece_model_path_;
  std::string piece_model_bytes_;
  SentenceEncoder sentence_encoder_{nullptr};
  std::shared_ptr<const RememberedEncodings> remembered_;  // see remember_corpus_encodings; null = none
};

// The caption part of a model checkpoint: with backbone "pieces" the piece
// model's file (pieces.model) and the config entry "pieces" naming it; with
// "use-lite" nothing (setup fetches the sentence encoder; it is not saved).
void save_checkpoint_captions(const std::string& dir, const CaptionReader& captions, nlohmann::json& config);
// Reads them back from checkpoint `dir` with config root `root`; a piece model
// other than config.vocab_size pieces fails through `fields` (naming the
// checkpoint's config.json and its hint).
CaptionReader load_checkpoint_captions(const std::string& dir, const nlohmann::json& root,
                                       const TextEncoderConfig& config, const train::JsonFields& fields);

struct TextEncoding {
  at::Tensor sentence;  // (B, output_dim) pooled sentence vector
  at::Tensor features;  // (B, P, dim) per-piece features (after the final LayerNorm); P = 1 with use-lite, 0 layers
                        // (without piece_memory)
  at::Tensor mask;      // (B, P) bool
};

class TextEncoderImpl : public torch::nn::Module {
 public:
  explicit TextEncoderImpl(const TextEncoderConfig& config);
  const TextEncoderConfig& config() const { return config_; }

  // Backbone "pieces": piece embeddings of the pieces that are whole words of
  // `vectors` ("▁dog" -> the vector of "dog") become those vectors; returns how
  // many did. Needs word_dim == vectors.dim().
  int64_t init_piece_embeddings(const PieceModel& pieces, const WordVectors& vectors);

  TextEncoding forward(const TextBatch& batch);

 private:
  at::Tensor input_tokens(const TextBatch& batch);  // (B, P, dim) before the positions
  at::Tensor dropped_encoder_features(const TextBatch& batch);  // use-lite: piece dropout in training

  TextEncoderConfig config_;
  torch::nn::Embedding piece_embedding_{nullptr};  // pieces: (vocab, word_dim or dim)
  torch::nn::Linear input_{nullptr};               // pieces: [piece ‖ word vector ‖ known] -> dim; use-lite: features -> dim
  at::Tensor positions_;                           // (max_pieces, dim) learnt; not with use-lite, 0 layers
  std::shared_ptr<layers::TransformerStackImpl> transformer_;
  torch::nn::Linear sentence_{nullptr};            // dim -> output_dim
  torch::nn::Linear encoder_sentence_{nullptr};    // use-lite: the encoder's sentence vector -> output_dim
  torch::nn::Linear piece_map_{nullptr};           // use-lite, piece_memory: features -> dim
};
TORCH_MODULE(TextEncoder);

}  // namespace nec::text

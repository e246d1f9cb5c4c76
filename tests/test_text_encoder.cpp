// text/encoder: caption batches (pieces + word channel, or the sentence
// encoder's outputs), the GloVe start of the piece embeddings, padding
// invariance, what a checkpoint keeps of each backbone, and the errors a user sees.
#include "nec/text/text_encoder.h"

#include "nec/motion/error.h"
#include "nec/train/checkpoint_io.h"
#include "nec/train/config_fields.h"
#include "test_support.h"
#include "text_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <filesystem>

#include <string>
#include <vector>

namespace nec {
namespace {

using text::TextBatch;
using text::TextEncoder;
using text::TextEncoderConfig;

// Piece dropout draws anew at every training forward pass and never in eval mode.
void expect_dropout_only_in_training(TextEncoder& encoder, const TextBatch& batch) {
  encoder->train();
  std::vector<double> outputs;
  for (int i = 0; i < 4; ++i) outputs.push_back(encoder->forward(batch).sentence.sum().item<double>());
  EXPECT_FALSE(outputs[0] == outputs[1] && outputs[1] == outputs[2] && outputs[2] == outputs[3]);
  encoder->eval();
  EXPECT_EQ(encoder->forward(batch).sentence.sum().item<double>(), encoder->forward(batch).sentence.sum().item<double>());
}

class TextEncoderTest : public testing::CorpusTextTest {
 protected:
  TextEncoderTest() : pieces_(text::PieceModel::load(pieces_path())), vectors_(text::WordVectors::load(vectors_path())) {
    config_.vocab_size = pieces_.vocab_size();
    config_.word_dim = 16;
    config_.dim = 32;
    config_.feedforward = 64;
    config_.output_dim = 24;
    config_.max_pieces = 16;
  }

  std::string error_of(const std::vector<std::string>& captions) {
    try {
      text::make_text_batch(captions, pieces_, &vectors_, config_, "query");
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  }

  text::PieceModel pieces_;
  text::WordVectors vectors_;
  TextEncoderConfig config_;
};

TEST_F(TextEncoderTest, EveryPieceCarriesTheVectorOfItsWord) {
  const TextBatch batch = text::make_text_batch({"A Hound scuttles!", "a dog walks forward"}, pieces_, &vectors_,
                                                config_, "query");
  const text::CaptionPieces hound = pieces_.split("a hound scuttles");
  ASSERT_GT(hound.ids.size(), 3u);  // "hound" and "scuttles" are not corpus words: several pieces each
  EXPECT_EQ(hound.words, (std::vector<std::string>{"a", "hound", "scuttles"}));
  const int64_t longest = std::max<int64_t>(hound.ids.size(), pieces_.split("a dog walks forward").ids.size());
  ASSERT_EQ(batch.ids.sizes(), (std::vector<int64_t>{2, longest}));
  ASSERT_EQ(batch.word_vectors.sizes(), (std::vector<int64_t>{2, longest, 16}));
  EXPECT_EQ(batch.mask[0].sum().item<int64_t>(), static_cast<int64_t>(hound.ids.size()));
  for (size_t p = 0; p < hound.ids.size(); ++p) {
    EXPECT_EQ(batch.ids[0][static_cast<int64_t>(p)].item<int64_t>(), hound.ids[p]);
    const std::string& word = hound.words[static_cast<size_t>(hound.word_of_piece[p])];
    const text::Vector expected = *vectors_.lookup(word);
    const at::Tensor got = batch.word_vectors[0][static_cast<int64_t>(p)];
    const double difference =
        (got - torch::tensor(expected)).abs().max().item<double>();
    EXPECT_EQ(difference, 0.0) << "piece " << p << " of word " << word;
    EXPECT_EQ(batch.word_known[0][static_cast<int64_t>(p)][0].item<float>(), 1.0f);
  }
  // Padding is zero and masked.
  for (int64_t p = static_cast<int64_t>(hound.ids.size()); p < longest; ++p) {
    EXPECT_EQ(batch.ids[0][p].item<int64_t>(), text::kPadPiece);
    EXPECT_FALSE(batch.mask[0][p].item<bool>());
    EXPECT_EQ(batch.word_vectors[0][p].abs().sum().item<float>(), 0.0f);
  }
  // A word without a vector is marked unknown.
  const TextBatch unknown = text::make_text_batch({"a zebra walks"}, pieces_, &vectors_, config_, "query");
  const text::CaptionPieces zebra = pieces_.split("a zebra walks");
  for (size_t p = 0; p < zebra.ids.size(); ++p) {
    const bool known = zebra.words[static_cast<size_t>(zebra.word_of_piece[p])] != "zebra";
    EXPECT_EQ(unknown.word_known[0][static_cast<int64_t>(p)][0].item<float>(), known ? 1.0f : 0.0f) << p;
  }
}

TEST_F(TextEncoderTest, SplitWordsWithAVectorAreReadAsUnknownPiecesWhenAsked) {
  const std::string caption = "a hound zebra walks";  // hound: pieces + vector; zebra: pieces, no vector
  const text::CaptionPieces split = pieces_.split(caption);
  const TextBatch as_cut = text::make_text_batch({caption}, pieces_, &vectors_, config_, "query");
  config_.read_split_words_by_vector = true;
  const TextBatch by_vector = text::make_text_batch({caption}, pieces_, &vectors_, config_, "query");
  int unknown = 0;
  for (size_t p = 0; p < split.ids.size(); ++p) {
    const std::string& word = split.words[static_cast<size_t>(split.word_of_piece[p])];
    const int64_t expected = word == "hound" ? text::kUnknownPiece : split.ids[p];
    EXPECT_EQ(as_cut.ids[0][static_cast<int64_t>(p)].item<int64_t>(), split.ids[p]) << p;
    EXPECT_EQ(by_vector.ids[0][static_cast<int64_t>(p)].item<int64_t>(), expected) << "piece " << p << " of " << word;
    unknown += expected == text::kUnknownPiece;
  }
  EXPECT_GE(unknown, 2);  // "hound" is cut into several pieces by the corpus piece model
  EXPECT_TRUE(torch::equal(as_cut.word_vectors, by_vector.word_vectors));
}

TEST_F(TextEncoderTest, WholeWordPiecesStartAtTheirWordVectors) {
  TextEncoder encoder(config_);
  const int64_t initialised = encoder->init_piece_embeddings(pieces_, vectors_);
  const std::vector<int> dog = pieces_.encode("dog");
  ASSERT_EQ(dog.size(), 1u);
  const at::Tensor weight = encoder->named_parameters()["piece_embedding.weight"];
  const double difference = (weight[dog[0]] - torch::tensor(*vectors_.lookup("dog"))).abs().max().item<double>();
  EXPECT_EQ(difference, 0.0);
  // Each of the corpus's 22 distinct words is one piece here, and no other piece is a word.
  EXPECT_EQ(initialised, 22);
  config_.word_dim = 8;
  EXPECT_THROW(TextEncoder(config_)->init_piece_embeddings(pieces_, vectors_), std::invalid_argument);
}

TEST_F(TextEncoderTest, OutputsHaveTheirShapesAndDoNotDependOnPadding) {
  torch::manual_seed(3);
  TextEncoder encoder(config_);
  encoder->eval();
  torch::NoGradGuard no_grad;
  const text::TextEncoding alone =
      encoder->forward(text::make_text_batch({"a dog walks"}, pieces_, &vectors_, config_, "query"));
  const text::TextEncoding batched = encoder->forward(
      text::make_text_batch({"a dog walks", "a spider crawls quickly in a circle"}, pieces_, &vectors_, config_, "query"));
  ASSERT_EQ(alone.sentence.sizes(), (std::vector<int64_t>{1, 24}));
  ASSERT_EQ(batched.features.size(2), 32);
  const double difference = (alone.sentence[0] - batched.sentence[0]).abs().max().item<double>();
  EXPECT_LT(difference, 1e-5) << "the second caption's length changed the first's vector by " << difference;
  EXPECT_GT((batched.sentence[0] - batched.sentence[1]).abs().max().item<double>(), 1e-3);
  // Eval mode reads every piece: the same output twice.
  const text::TextEncoding again =
      encoder->forward(text::make_text_batch({"a dog walks"}, pieces_, &vectors_, config_, "query"));
  EXPECT_EQ((again.sentence - alone.sentence).abs().max().item<double>(), 0.0);
}

TEST_F(TextEncoderTest, ACaptionWithAnUnseenSynonymIsReadLikeItsWord) {
  // Learn the creature of each corpus caption (6 classes) from the sentence
  // vector, then ask about words no caption used: "hound" (near "dog" in the
  // word vectors) and "scuttles" (near "crawls"), cut into pieces the encoder
  // never saw in training.
  torch::manual_seed(1);
  config_.piece_dropout = 0.3;
  TextEncoder encoder(config_);
  encoder->init_piece_embeddings(pieces_, vectors_);
  torch::nn::Linear head(config_.output_dim, 6);
  std::vector<at::Tensor> parameters = encoder->parameters();
  for (const at::Tensor& p : head->parameters()) parameters.push_back(p);
  torch::optim::Adam optimizer(parameters, torch::optim::AdamOptions(3e-3));
  const std::vector<std::string> captions = testing::caption_corpus();  // creature-major: 30 per creature
  const TextBatch batch = text::make_text_batch(captions, pieces_, &vectors_, config_, "corpus");
  const at::Tensor creature = torch::div(torch::arange(static_cast<int64_t>(captions.size())), 30, "floor");
  double loss_value = 0;
  for (int step = 0; step < 60; ++step) {
    optimizer.zero_grad();
    const at::Tensor loss = torch::cross_entropy_loss(head(encoder->forward(batch).sentence), creature);
    loss.backward();
    optimizer.step();
    loss_value = loss.item<double>();
  }
  EXPECT_LT(loss_value, 0.05);
  encoder->eval();
  torch::NoGradGuard no_grad;
  const TextBatch queries = text::make_text_batch({"a hound walks forward", "a hound scuttles slowly", "a horse jumps"},
                                                  pieces_, &vectors_, config_, "query");
  const at::Tensor predicted = head(encoder->forward(queries).sentence).argmax(1);
  EXPECT_EQ(predicted[0].item<int64_t>(), 0) << "'hound' read as creature " << predicted[0].item<int64_t>();  // dog
  EXPECT_EQ(predicted[1].item<int64_t>(), 0) << "'hound' read as creature " << predicted[1].item<int64_t>();
  EXPECT_EQ(predicted[2].item<int64_t>(), 5);  // horse
}

TEST_F(TextEncoderTest, EmptyLetterlessAndOverlongCaptionsAreRefused) {
  EXPECT_EQ(error_of({""}), "query: empty");
  EXPECT_EQ(error_of({"a dog walks", "?!"}), "query (caption 2): no letters in '?!'");
  const std::string overlong = "a dog walks forward then a spider crawls to the left then a snake turns";
  const std::string message = error_of({overlong});
  EXPECT_NE(message.find("pieces, more than the 16 the text encoder takes"), std::string::npos) << message;
  config_.word_dim = 16;
  EXPECT_THROW(text::make_text_batch({"a dog"}, pieces_, nullptr, config_, "query"), std::invalid_argument);
}

TEST_F(TextEncoderTest, PieceDropoutActsOnlyInTraining) {
  config_.piece_dropout = 0.5;
  config_.dropout = 0.0;
  torch::manual_seed(0);
  TextEncoder encoder(config_);
  const TextBatch batch = text::make_text_batch({"a dog walks forward"}, pieces_, &vectors_, config_, "query");
  expect_dropout_only_in_training(encoder, batch);
}

// The use-lite backbone: the frozen sentence encoder under a small trainable head.
class UseLiteTextEncoderTest : public ::testing::Test {
 protected:
  UseLiteTextEncoderTest() {
    config_.backbone = text::kUseLiteBackbone;
    config_.word_dim = 0;
    config_.dim = 32;
    config_.heads = 2;
    config_.feedforward = 64;
    config_.layers = 1;
    config_.output_dim = 24;
    config_.max_pieces = 16;
    reader_ = text::CaptionReader::for_training(config_, "");
  }

  TextEncoderConfig config_;
  text::CaptionReader reader_;
};

TEST_F(UseLiteTextEncoderTest, BatchesHoldTheSentenceEncodersOutputsForTheNormalizedCaptions) {
  const TextBatch batch = reader_.read({"A Dog trots, 3 times!", "a spider crawls"}, nullptr, "query");
  const text::SentenceEncoding expected =
      text::shared_sentence_encoder()->encode({"a dog trots three times", "a spider crawls"});
  ASSERT_EQ(batch.encoder_features.sizes(), expected.features.sizes());
  EXPECT_EQ(batch.encoder_features.size(2), text::kUseLiteWidth);
  EXPECT_TRUE(torch::equal(batch.mask, expected.mask));
  EXPECT_TRUE(torch::allclose(batch.encoder_features, expected.features));
  EXPECT_TRUE(torch::allclose(batch.encoder_sentence, expected.sentence));
  EXPECT_FALSE(batch.ids.defined());
  EXPECT_EQ(reader_.pieces(), nullptr);
  EXPECT_EQ(reader_.count_pieces("a spider crawls"), batch.mask[1].sum().item<int64_t>());
}

// Largest difference of two tensors relative to the largest magnitude of `expected`.
double relative_difference(const at::Tensor& read, const at::Tensor& expected) {
  return (read - expected).abs().max().item<double>() / expected.abs().max().item<double>();
}

// A trainer's reader keeps the encodings of its corpus's captions: a batch of
// those, repeats and new captions reads what a reader keeping nothing reads,
// and copies of the reader share what was kept.
TEST_F(UseLiteTextEncoderTest, RememberedCorpusEncodingsReadLikeFreshOnes) {
  DatasetCache cache;
  const std::vector<std::pair<Split, std::vector<std::string>>> clips = {
      {Split::Train, {"a dog walks", "A dog walks!"}},
      {Split::Val, {"a spider crawls quickly in a circle"}},
      {Split::Test, {"a bird flaps its wings"}},
  };
  for (const auto& [split, captions] : clips) {
    CacheClip clip;
    clip.id = "clip" + std::to_string(cache.clips.size());
    clip.split = split;
    clip.captions = captions;
    cache.clips.push_back(clip);
  }
  text::CaptionReader remembering = reader_;
  remembering.remember_corpus_encodings(cache, size_t{1} << 24);
  const text::CaptionReader copy = remembering;
  EXPECT_EQ(copy.remembered_captions(), 2u);  // "a dog walks" once; not the test clip's caption
  EXPECT_EQ(reader_.remembered_captions(), 0u);
  const std::vector<std::vector<std::string>> batches = {
      {"a dog walks", "a spider crawls quickly in a circle"},
      {"a spider crawls quickly in a circle", "a bird flaps its wings", "A dog walks!", "a bird flaps its wings"},
      {"a bird flaps its wings"},
  };
  for (const std::vector<std::string>& captions : batches) {
    const TextBatch fresh = reader_.read(captions, nullptr, "query");
    for (const text::CaptionReader* reader : {&copy, static_cast<const text::CaptionReader*>(&remembering)}) {
      const TextBatch read = reader->read(captions, nullptr, "query");
      ASSERT_EQ(read.encoder_features.sizes(), fresh.encoder_features.sizes()) << captions.size();
      EXPECT_TRUE(torch::equal(read.mask, fresh.mask));
      // Float rounding of products of other shapes (measured: 2e-6 of the largest feature).
      EXPECT_LT(relative_difference(read.encoder_features, fresh.encoder_features), 1e-5);
      EXPECT_LT(relative_difference(read.encoder_sentence, fresh.encoder_sentence), 1e-5);
    }
  }
  // Reading a kept caption again gives the same numbers bit for bit.
  EXPECT_TRUE(torch::equal(copy.read(batches[0], nullptr, "query").encoder_features,
                           remembering.read(batches[0], nullptr, "query").encoder_features));
  // A budget too small to keep anything keeps nothing and reads the same; errors still name the caption.
  text::CaptionReader keeping_nothing = reader_;
  keeping_nothing.remember_corpus_encodings(cache, 16);
  EXPECT_EQ(keeping_nothing.remembered_captions(), 0u);
  EXPECT_LT(relative_difference(keeping_nothing.read(batches[1], nullptr, "query").encoder_sentence,
                                reader_.read(batches[1], nullptr, "query").encoder_sentence),
            1e-5);
  EXPECT_THROW(remembering.read({"a dog walks", ""}, nullptr, "query"), InputError);
}

TEST_F(UseLiteTextEncoderTest, OutputsHaveTheirShapesAndDoNotDependOnPadding) {
  torch::manual_seed(3);
  TextEncoder encoder(config_);
  encoder->eval();
  torch::NoGradGuard no_grad;
  const text::TextEncoding alone = encoder->forward(reader_.read({"a dog walks"}, nullptr, "query"));
  const text::TextEncoding batched =
      encoder->forward(reader_.read({"a dog walks", "a spider crawls quickly in a circle"}, nullptr, "query"));
  ASSERT_EQ(alone.sentence.sizes(), (std::vector<int64_t>{1, 24}));
  ASSERT_EQ(batched.features.size(2), 32);
  EXPECT_LT((alone.sentence[0] - batched.sentence[0]).abs().max().item<double>(), 1e-5);
  EXPECT_GT((batched.sentence[0] - batched.sentence[1]).abs().max().item<double>(), 1e-3);
  // The module holds only the head: the sentence encoder stays outside, frozen.
  for (const auto& named : encoder->named_parameters()) {
    EXPECT_LE(named.value().numel(), int64_t{512} * 32) << named.key();
  }
}

TEST_F(UseLiteTextEncoderTest, AHeadOnTheSentenceVectorReadsWordsNoCaptionUsed) {
  // As the pieces test above, but with no word vectors given: the creature of
  // each corpus caption (6 classes) from the sentence vector, then captions
  // whose creature words no training caption used.
  config_.layers = 0;
  config_.dim = 128;
  torch::manual_seed(1);
  TextEncoder encoder(config_);
  torch::nn::Linear head(config_.output_dim, 6);
  std::vector<at::Tensor> parameters = encoder->parameters();
  for (const at::Tensor& p : head->parameters()) parameters.push_back(p);
  torch::optim::Adam optimizer(parameters, torch::optim::AdamOptions(3e-3));
  const std::vector<std::string> captions = testing::caption_corpus();  // creature-major: 30 per creature
  const TextBatch batch = reader_.read(captions, nullptr, "corpus");
  const at::Tensor creature = torch::div(torch::arange(static_cast<int64_t>(captions.size())), 30, "floor");
  for (int step = 0; step < 60; ++step) {
    optimizer.zero_grad();
    torch::cross_entropy_loss(head(encoder->forward(batch).sentence), creature).backward();
    optimizer.step();
  }
  encoder->eval();
  torch::NoGradGuard no_grad;
  // dog 0, spider 1, snake 2, person 3, bird 4, horse 5
  const std::vector<std::pair<std::string, int64_t>> queries{{"a puppy walks forward", 0},
                                                             {"a hound runs quickly", 0},
                                                             {"the tarantula crawls slowly", 1},
                                                             {"a serpent turns to the left", 2},
                                                             {"a woman jumps", 3},
                                                             {"a man runs forward", 3},
                                                             {"a sparrow walks", 4},
                                                             {"a pony trots to the right", 5}};
  std::vector<std::string> texts;
  for (const auto& query : queries) texts.push_back(query.first);
  const at::Tensor predicted = head(encoder->forward(reader_.read(texts, nullptr, "query")).sentence).argmax(1);
  // Seeds differ in one query or none (e.g. "tarantula" read as a snake): 7 of 8 at least.
  int right = 0;
  std::string misses;
  for (size_t i = 0; i < queries.size(); ++i) {
    const int64_t got = predicted[static_cast<int64_t>(i)].item<int64_t>();
    if (got == queries[i].second) {
      ++right;
    } else {
      misses += " '" + queries[i].first + "' read as creature " + std::to_string(got) + ";";
    }
  }
  EXPECT_GE(right, 7) << misses;
}

TEST_F(UseLiteTextEncoderTest, WithNoLayersTheSentenceVectorIsTheOnlyPieceAndLongCaptionsAreRead) {
  config_.layers = 0;
  const text::CaptionReader reader = text::CaptionReader::for_training(config_, "");
  TextEncoder encoder(config_);
  encoder->eval();
  torch::NoGradGuard no_grad;
  const std::string long_caption = "a dog walks forward then a spider crawls to the left then a snake turns around";
  const TextBatch batch = reader.read({"a dog walks", long_caption}, nullptr, "query");
  EXPECT_GT(batch.mask[1].sum().item<int64_t>(), config_.max_pieces);
  const text::TextEncoding out = encoder->forward(batch);
  ASSERT_EQ(out.features.sizes(), (std::vector<int64_t>{2, 1, 32}));
  EXPECT_TRUE(out.mask.all().item<bool>());
  // The output is a function of the sentence vector alone.
  TextBatch other = batch;
  other.encoder_features = torch::zeros_like(batch.encoder_features);
  EXPECT_TRUE(torch::equal(encoder->forward(other).sentence, out.sentence));
  EXPECT_GT((out.sentence[0] - out.sentence[1]).abs().max().item<double>(), 1e-3);
}

TEST_F(UseLiteTextEncoderTest, PieceMemoryMapsEachPieceAloneAndKeepsTheSentenceHead) {
  config_.layers = 0;
  config_.piece_memory = true;
  const text::CaptionReader reader = text::CaptionReader::for_training(config_, "");
  torch::manual_seed(1);
  TextEncoder encoder(config_);
  encoder->eval();
  torch::NoGradGuard no_grad;
  const TextBatch batch = reader.read({"a dog walks", "a spider crawls quickly to the left"}, nullptr, "query");
  const text::TextEncoding out = encoder->forward(batch);
  const int64_t pieces = batch.mask.size(1);
  ASSERT_EQ(out.features.sizes(), (std::vector<int64_t>{2, pieces, 32}));
  EXPECT_TRUE(torch::equal(out.mask, batch.mask));
  // Each piece's features depend on that piece's encoder features alone: changing the last piece of the
  // long caption changes only its row.
  TextBatch changed = batch;
  changed.encoder_features = batch.encoder_features.clone();
  changed.encoder_features[1][pieces - 1] += 1.0;
  const text::TextEncoding moved = encoder->forward(changed);
  EXPECT_TRUE(torch::equal(moved.features.narrow(1, 0, pieces - 1), out.features.narrow(1, 0, pieces - 1)));
  EXPECT_GT((moved.features[1][pieces - 1] - out.features[1][pieces - 1]).abs().max().item<double>(), 1e-3);
  // The sentence vector is the sentence head's, as without piece_memory.
  EXPECT_TRUE(torch::equal(moved.sentence, out.sentence));
  config_.layers = 2;
  EXPECT_THROW(config_.validate(), std::invalid_argument);
  // Captions longer than max_pieces are refused, as the per-piece features are read.
  EXPECT_THROW(reader.read({"a dog walks forward then a spider crawls to the left then a snake turns around"}, nullptr, "q"),
               InputError);
}

TEST_F(UseLiteTextEncoderTest, PieceDropoutZeroesFeaturesOnlyInTraining) {
  config_.piece_dropout = 0.5;
  config_.dropout = 0.0;
  torch::manual_seed(0);
  TextEncoder encoder(config_);
  const TextBatch batch = reader_.read({"a dog walks forward"}, nullptr, "query");
  expect_dropout_only_in_training(encoder, batch);
}

TEST_F(UseLiteTextEncoderTest, EmptyAndOverlongCaptionsAreRefusedNamingThem) {
  const auto error_of = [&](const std::vector<std::string>& captions) -> std::string {
    try {
      reader_.read(captions, nullptr, "query");
    } catch (const InputError& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(error_of({"a dog walks", ""}), "query (caption 2): empty");
  const std::string message = error_of({"a dog walks forward then a spider crawls to the left then a snake turns around"});
  EXPECT_NE(message.find("pieces, more than the 16 the text encoder takes"), std::string::npos) << message;
}

TEST_F(UseLiteTextEncoderTest, ConfigsNameTheirBackboneAndOldOnesReadPieces) {
  TextEncoderConfig bad = config_;
  bad.word_dim = 100;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = config_;
  bad.backbone = "glove";
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  nlohmann::json written = {{"text", train::write_config(config_)}};
  EXPECT_EQ(written["text"]["backbone"], "use-lite");
  written["text"].erase("backbone");  // a checkpoint from before the field
  written["text"]["word_dim"] = 100;
  const TextEncoderConfig old = train::read_config_object<TextEncoderConfig>(written, "text", {"config.json", "", "", true});
  EXPECT_EQ(old.backbone, text::kPiecesBackbone);
}

TEST_F(UseLiteTextEncoderTest, ACheckpointKeepsThePieceModelOnlyWhenItReadsPieces) {
  testing::TempDir dir;
  const train::JsonFields fields((dir.path() / "config.json").string(), "hint");
  nlohmann::json root = nlohmann::json::object();
  text::save_checkpoint_captions(dir.path().string(), reader_, root);
  EXPECT_FALSE(root.contains("pieces"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "pieces.model"));
  const text::CaptionReader loaded = text::load_checkpoint_captions(dir.path().string(), root, config_, fields);
  EXPECT_EQ(loaded.pieces(), nullptr);
  EXPECT_TRUE(torch::equal(loaded.read({"a dog"}, nullptr, "q").encoder_sentence,
                           reader_.read({"a dog"}, nullptr, "q").encoder_sentence));

  const std::string spm = (dir.path() / "corpus.model").string();
  testing::train_corpus_piece_model(spm);
  TextEncoderConfig pieces_config;
  const text::CaptionReader pieces = text::CaptionReader::for_training(pieces_config, spm);
  testing::TempDir saved;
  nlohmann::json pieces_root = nlohmann::json::object();
  text::save_checkpoint_captions(saved.path().string(), pieces, pieces_root);
  EXPECT_EQ(pieces_root["pieces"], "pieces.model");
  const text::CaptionReader reloaded = text::load_checkpoint_captions(saved.path().string(), pieces_root, pieces_config, fields);
  ASSERT_NE(reloaded.pieces(), nullptr);
  EXPECT_EQ(reloaded.pieces()->vocab_size(), pieces_config.vocab_size);
  pieces_config.vocab_size += 1;
  EXPECT_THROW(text::load_checkpoint_captions(saved.path().string(), pieces_root, pieces_config, fields), InputError);
}

}  // namespace
}  // namespace nec

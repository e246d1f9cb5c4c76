// text/encoder: caption batches (pieces + word channel), the GloVe start of
// the piece embeddings, padding invariance, and the errors a user sees.
#include "nec/text/text_encoder.h"

#include "nec/motion/error.h"
#include "test_support.h"
#include "text_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <string>
#include <vector>

namespace nec {
namespace {

using text::TextBatch;
using text::TextEncoder;
using text::TextEncoderConfig;

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
  EXPECT_EQ(error_of({""}), "query: the caption is empty");
  EXPECT_EQ(error_of({"a dog walks", "?!"}), "query (caption 2): the caption has no letters: '?!'");
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
  encoder->train();
  std::vector<double> outputs;
  for (int i = 0; i < 4; ++i) outputs.push_back(encoder->forward(batch).sentence.sum().item<double>());
  EXPECT_FALSE(outputs[0] == outputs[1] && outputs[1] == outputs[2] && outputs[2] == outputs[3]);
  encoder->eval();
  EXPECT_EQ(encoder->forward(batch).sentence.sum().item<double>(), encoder->forward(batch).sentence.sum().item<double>());
}

}  // namespace
}  // namespace nec

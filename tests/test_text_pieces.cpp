// text/caption_text.h and text/piece_model.h: caption normalization, and the
// sentencepiece bridge trained and used inside a process that runs torch.
#include "nec/text/caption_text.h"
#include "nec/text/piece_model.h"

#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "test_support.h"
#include "text_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <string>
#include <vector>

namespace nec {
namespace {

using text::caption_words;
using text::checked_caption;
using text::normalize_caption;

std::string error_of(const std::string& caption) {
  try {
    checked_caption(caption, "query");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(CaptionText, CaseDigitsAndPunctuationAreNormalized) {
  EXPECT_EQ(normalize_caption("A Dog trots, 3 times!"), "a dog trots three times");
  EXPECT_EQ(normalize_caption("  The spider's LEFT-hand legs\ttwitch.  "), "the spiders left hand legs twitch");
  EXPECT_EQ(normalize_caption("walks 150 steps, then 20 more (3rd try)"), "walks 150 steps then twenty more three rd try");
  EXPECT_EQ(normalize_caption("Café — très vite"), "café \xE2\x80\x94 très vite");
  EXPECT_EQ(normalize_caption("?!..."), "");
  EXPECT_EQ(caption_words("a dog trots"), (std::vector<std::string>{"a", "dog", "trots"}));
  EXPECT_TRUE(caption_words("").empty());
}

TEST(CaptionText, EmptyCaptionsAndCaptionsWithoutLettersAreRefused) {
  EXPECT_EQ(error_of(""), "query: empty");
  EXPECT_EQ(error_of(" ?! "), "query: no letters in ' ?! '");
  EXPECT_EQ(error_of("42"), "query: no letters in '42'");
  EXPECT_EQ(checked_caption("Run!", "query"), "run");
}

using testing::caption_corpus;

class CaptionPieces : public testing::SharedFolderTest {};

TEST_F(CaptionPieces, TrainAndEncodeInsideAProcessThatRunsTorch) {
  const at::Tensor a = torch::randn({64, 64});
  const float before = (a.matmul(a.t()) - a.matmul(a.t())).abs().max().item<float>();
  EXPECT_EQ(before, 0.0f);

  const std::string model_path = path("spm.model");
  text::PieceTrainOptions options;
  options.vocab_size = 120;
  text::train_piece_model(caption_corpus(), options, model_path);
  const text::PieceModel model = text::PieceModel::load(model_path);
  EXPECT_GT(model.vocab_size(), 20);
  EXPECT_LE(model.vocab_size(), 120);
  EXPECT_EQ(model.piece(text::kPadPiece), "<pad>");
  EXPECT_EQ(model.piece(text::kUnknownPiece), "<unk>");
  for (const std::string& caption : caption_corpus()) {
    const std::vector<int> ids = model.encode(caption);
    ASSERT_FALSE(ids.empty()) << caption;
    EXPECT_EQ(model.decode(ids), caption);
    // One word start per word.
    int starts = 0;
    for (const int id : ids) starts += model.starts_word(id) ? 1 : 0;
    EXPECT_EQ(starts, static_cast<int>(caption_words(caption).size())) << caption;
  }
  // Frequent words are whole pieces.
  const std::vector<int> dog = model.encode("dog");
  ASSERT_EQ(dog.size(), 1u);
  EXPECT_EQ(model.piece(dog[0]), "\xE2\x96\x81" "dog");
  // A word no caption used still encodes, from smaller pieces, and decodes back.
  const std::vector<int> hound = model.encode("a hound sprints");
  EXPECT_GT(hound.size(), 3u);
  EXPECT_EQ(model.decode(hound), "a hound sprints");

  // The same captions give the same pieces in the same order.
  const std::string again = path("spm_again.model");
  text::train_piece_model(caption_corpus(), options, again);
  const text::PieceModel second = text::PieceModel::load(again);
  ASSERT_EQ(second.vocab_size(), model.vocab_size());
  for (int id = 0; id < model.vocab_size(); ++id) EXPECT_EQ(second.piece(id), model.piece(id)) << id;

  const at::Tensor b = torch::ones({8, 8}).matmul(torch::ones({8, 8}));
  EXPECT_EQ(b.sum().item<float>(), 512.0f);
}

TEST_F(CaptionPieces, BadModelFilesAndIdsGetClearErrors) {
  const std::string missing = path("none.model");
  try {
    text::PieceModel::load(missing);
    FAIL() << "loaded a missing file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no such piece model"), std::string::npos) << e.what();
  }
  const std::string garbage = path("garbage.model");
  write_file_atomic(garbage, "this is not a model");
  try {
    text::PieceModel::load(garbage);
    FAIL() << "loaded garbage";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not a sentencepiece model"), std::string::npos) << e.what();
  }
  EXPECT_THROW(text::train_piece_model({}, {}, path("empty.model")), InputError);
  text::PieceTrainOptions options;
  options.vocab_size = 100;
  text::train_piece_model(caption_corpus(), options, path("ok.model"));
  const text::PieceModel model = text::PieceModel::load(path("ok.model"));
  EXPECT_THROW(model.decode({model.vocab_size()}), std::invalid_argument);
  EXPECT_THROW(model.piece(-1), std::invalid_argument);
  options.model_type = "wordpiece";
  EXPECT_THROW(text::train_piece_model(caption_corpus(), options, path("x.model")), std::invalid_argument);
}

}  // namespace
}  // namespace nec

// The sentence encoder's piece tokenizer on small vocabularies made here: each
// rule of the package's runner (text/sentence_pieces.h) checked on a case where
// a plain best-path search would answer otherwise.
#include "nec/motion/error.h"
#include "nec/text/sentence_pieces.h"

#include "test_support.h"

#include <gtest/gtest.h>

namespace nec::text {
namespace {

using testing::TempDir;

// A vocab.json: the six reserved ids, then `pieces` ([piece, score] JSON pairs) from id 6 on.
std::string vocabulary(const TempDir& dir, const std::string& pieces) {
  return dir.write("vocab.json", R"([["\ufffd", 0], ["<s>", 0], ["</s>", 0], ["extra_token_id_1", 0],)"
                                 R"( ["extra_token_id_2", 0], ["extra_token_id_3", 0], )" + pieces + "]");
}

TEST(SentencePieces, SpacesBecomeWordStartsAndTheBestPathWins) {
  const TempDir dir;
  // 6 ▁, 7 a, 8 b, 9 ab, 10 ▁a, 11 ▁ab
  const SentencePieces pieces = SentencePieces::load(
      vocabulary(dir, R"(["\u2581", -2], ["a", -3], ["b", -3], ["ab", -4], ["\u2581a", -2], ["\u2581ab", -1])"));
  EXPECT_EQ(pieces.size(), 12);
  EXPECT_EQ(pieces.encode("ab"), (std::vector<int>{11}));           // ▁ab (-1) beats ▁a b (-5) and ▁ ab (-6)
  EXPECT_EQ(pieces.encode("ab a"), (std::vector<int>{11, 10}));     // ▁ab ▁a
  EXPECT_EQ(pieces.encode("  a"), (std::vector<int>{6, 6, 10}));    // every space is a ▁, none collapsed
  EXPECT_EQ(pieces.encode("ba"), (std::vector<int>{6, 8, 7}));      // no ▁b: ▁ b a
  EXPECT_TRUE(pieces.encode("").empty());
}

TEST(SentencePieces, UnknownCharactersAreOnePieceAndRunsOfThemOne) {
  const TempDir dir;
  const SentencePieces pieces = SentencePieces::load(vocabulary(dir, R"(["\u2581", -1], ["a", -1])"));
  EXPECT_EQ(pieces.encode("a"), (std::vector<int>{6, 7}));
  EXPECT_EQ(pieces.encode("a\xe6\x9d\xb1\xe4\xba\xac"), (std::vector<int>{6, 7, 0}));  // a東京: one unknown for both
  EXPECT_EQ(pieces.encode("a\txa"), (std::vector<int>{6, 7, 0, 7}));                  // a tab is no space
  EXPECT_EQ(pieces.encode("<s>"), (std::vector<int>{6, 0}));                          // reserved texts are not pieces
}

TEST(SentencePieces, NfkcKeepsCase) {
  const TempDir dir;
  // 6 ▁, 7 A, 8 a, 9 fi, 10 f, 11 i
  const SentencePieces pieces = SentencePieces::load(
      vocabulary(dir, R"(["\u2581", -1], ["A", -1], ["a", -1], ["fi", -1], ["f", -2], ["i", -2])"));
  EXPECT_EQ(pieces.encode("A"), (std::vector<int>{6, 7}));
  EXPECT_EQ(pieces.encode("\xef\xbc\xa1"), (std::vector<int>{6, 7}));  // full-width Ａ is A
  EXPECT_EQ(pieces.encode("\xef\xac\x81"), (std::vector<int>{6, 9}));  // the ligature ﬁ is fi
  EXPECT_EQ(pieces.encode("a\xc2\xa0" "a"), (std::vector<int>{6, 8, 6, 8}));  // NFKC makes a no-break space a space
}

TEST(SentencePieces, TheRunnersQuirksAreKept) {
  const TempDir dir;
  // 6 ▁, 7 x, 8 ▁x (null: 0), 9 y, 10 y again: the last listing counts.
  const SentencePieces pieces =
      SentencePieces::load(vocabulary(dir, R"(["\u2581", -1], ["x", -1], ["\u2581x", null], ["y", -1], ["y", -2])"));
  // ▁x sums to 0, which the runner reads as "not reached": ▁ x (-2) replaces it although it scores less.
  EXPECT_EQ(pieces.encode("x"), (std::vector<int>{6, 7}));
  EXPECT_EQ(pieces.encode("xy"), (std::vector<int>{6, 7, 10}));
  // Equal sums: the piece that starts later wins. 6 ▁, 7 ab, 8 a, 9 b: ▁ ab and ▁ a b both sum to -3.
  const TempDir tie;
  const SentencePieces ties = SentencePieces::load(vocabulary(tie, R"(["\u2581", -1], ["ab", -2], ["a", -1], ["b", -1])"));
  EXPECT_EQ(ties.encode("ab"), (std::vector<int>{6, 8, 9}));
}

TEST(SentencePieces, BadVocabularyNamesTheFileAndTheSetupCommand) {
  const TempDir dir;
  for (const std::string& text : {std::string("not json"), std::string("{}"), std::string(R"([["a", "b"]])")}) {
    const std::string path = dir.write("vocab.json", text);
    try {
      SentencePieces::load(path);
      ADD_FAILURE() << "accepted " << text;
    } catch (const InputError& e) {
      EXPECT_TRUE(testing::contains(e.what(), path)) << e.what();
      EXPECT_TRUE(testing::contains(e.what(), "setup_sentence_encoder.sh")) << e.what();
    }
  }
  EXPECT_THROW(SentencePieces::load(dir / "missing.json"), InputError);
}

}  // namespace
}  // namespace nec::text

// Helpers of the tests that read captions: a small caption corpus, a piece
// model trained on it, and hand-made word vectors with a known geometry.
#pragma once

#include "test_support.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace nec::testing {

// Captions like the zoo's: "a <creature> <verb> <how>" over 6 creatures,
// 6 verbs and 5 ways (180 captions).
std::vector<std::string> caption_corpus();

// Trains a BPE piece model on caption_corpus() (at most `vocab_size` pieces) to `path`.
void train_corpus_piece_model(const std::string& path, int vocab_size = 120);

// Word vectors of width `dim` (>= 8) for every word of caption_corpus() and a
// few words it never uses: "hound" lies close to "dog" (cosine > 0.95),
// "sprints" to "runs", "scuttles" to "crawls"; the corpus words are nearly
// orthogonal to one another. Written with text::write_word_vectors to `path`.
void write_corpus_word_vectors(const std::string& path, int dim = 16);

// A test suite with a piece model and 16-d word vectors of caption_corpus(),
// made once for the suite in a temporary folder.
class CorpusTextTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  static std::string pieces_path();
  static std::string vectors_path();

 private:
  static TempDir* folder_;
};

}  // namespace nec::testing

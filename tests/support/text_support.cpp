// Caption corpus, piece model and word vectors for the tests.
#include "text_support.h"

#include "nec/motion/random.h"
#include "nec/text/caption_text.h"
#include "nec/text/piece_model.h"
#include "nec/text/word_vectors.h"

#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

namespace nec::testing {

std::vector<std::string> caption_corpus() {
  std::vector<std::string> out;
  for (const char* creature : {"dog", "spider", "snake", "person", "bird", "horse"}) {
    for (const char* verb : {"walks", "runs", "trots", "crawls", "turns", "jumps"}) {
      for (const char* how : {"forward", "to the left", "to the right", "slowly", "quickly in a circle"}) {
        out.push_back(std::string("a ") + creature + " " + verb + " " + how);
      }
    }
  }
  return out;
}

void train_corpus_piece_model(const std::string& path, int vocab_size) {
  text::PieceTrainOptions options;
  options.vocab_size = vocab_size;
  text::train_piece_model(caption_corpus(), options, path);
}

void write_corpus_word_vectors(const std::string& path, int dim) {
  if (dim < 8) throw std::invalid_argument("write_corpus_word_vectors: dim must be >= 8");
  std::set<std::string> corpus_words;
  for (const std::string& caption : caption_corpus()) {
    for (const std::string& word : text::caption_words(caption)) corpus_words.insert(word);
  }
  std::map<std::string, text::Vector> vectors;
  SplitMix64 random(17);
  for (const std::string& word : corpus_words) {
    text::Vector v(static_cast<size_t>(dim));
    for (float& x : v) x = static_cast<float>(random.uniform(-1.0, 1.0));
    vectors[word] = v;
  }
  // Near synonyms: the word's vector plus a little noise.
  for (const auto& [synonym, word] : std::map<std::string, std::string>{{"hound", "dog"}, {"sprints", "runs"}, {"scuttles", "crawls"}}) {
    text::Vector v = vectors.at(word);
    for (float& x : v) x += static_cast<float>(random.uniform(-0.05, 0.05));
    vectors[synonym] = v;
  }
  std::vector<std::string> words;
  std::vector<float> rows;
  for (const auto& [word, v] : vectors) {
    words.push_back(word);
    rows.insert(rows.end(), v.begin(), v.end());
  }
  text::write_word_vectors(path, words, rows, dim);
}

TempDir* CorpusTextTest::folder_ = nullptr;

void CorpusTextTest::SetUpTestSuite() {
  folder_ = new TempDir();
  train_corpus_piece_model(pieces_path());
  write_corpus_word_vectors(vectors_path(), 16);
}

void CorpusTextTest::TearDownTestSuite() {
  delete folder_;
  folder_ = nullptr;
}

std::string CorpusTextTest::pieces_path() { return *folder_ / "spm.model"; }
std::string CorpusTextTest::vectors_path() { return *folder_ / "words.bin"; }

}  // namespace nec::testing

// Caption augmentation by word-vector neighbours: in training, a caption word
// is sometimes replaced by a nearby word of the word vectors that no training
// caption uses ("walks" -> "strolls"), so that a text encoder learns to read
// the word channel of words it never saw, as users write them.
//
//   SynonymTable table = SynonymTable::build(vectors, train_caption_words, {});
//   SplitMix64 random(seed);
//   std::string caption = table.rewrite("a dog walks forward", 0.3, random);  // e.g. "a dog strolls forward"
//
// A word's synonyms are the vector words whose closest caption word (by
// cosine) is that word, at least min_cosine close, the per_word closest of
// them. Two rules keep a rewrite meaning what the caption meant: a synonym is
// never another caption word (GloVe puts "left" next to "right", "slowly" next
// to "quickly"), and a word near two caption words goes to the closer one only
// ("backwards" is a synonym of "backward", never of "forward").
#pragma once

#include "nec/motion/random.h"
#include "nec/text/word_vectors.h"

#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace nec::text {

struct SynonymOptions {
  int per_word = 8;         // most synonyms kept per caption word, e.g. 8
  double min_cosine = 0.6;  // least cosine between a word and its synonym, e.g. 0.6

  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

class SynonymTable {
 public:
  SynonymTable() = default;

  // Synonyms of every word of `caption_words` (lower case; duplicates and
  // words without a vector are ignored) among the vector words made of ASCII
  // lower-case letters only. One pass of the whole vocabulary (341k words:
  // about a second).
  static SynonymTable build(const WordVectors& vectors, const std::vector<std::string>& caption_words,
                            const SynonymOptions& options);

  // The synonyms of `word`, closest first; empty when it has none.
  const std::vector<std::string>& synonyms_of(const std::string& word) const;
  // Caption words with at least one synonym.
  size_t word_count() const { return synonyms_.size(); }
  size_t synonym_count() const;

  // `normalized` (normalize_caption's form) with each word that has synonyms
  // replaced, with chance `probability`, by one of them drawn uniformly.
  std::string rewrite(std::string_view normalized, double probability, SplitMix64& random) const;

 private:
  std::map<std::string, std::vector<std::string>> synonyms_;
};

}  // namespace nec::text

// nec text train-tokenizer / nec text pieces: the caption piece model.
#include "command_line.h"
#include "commands.h"

#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/text/caption_text.h"
#include "nec/text/piece_model.h"

#include <fmt/format.h>

#include <filesystem>
#include <map>
#include <set>

namespace nec::app {

int run_train_tokenizer(int argc, char** argv) {
  CommandLine cli("nec text train-tokenizer",
                  "Train the caption piece model (sentencepiece) on every caption of the train split of dataset\n"
                  "caches (all caption levels), after nec's caption normalization: lower case, numbers up to\n"
                  "twenty spelled out, punctuation a word break. The val and test captions stay unseen, so that\n"
                  "retrieval is measured on words the model may not know.");
  cli.option("--data", "CACHES", "", "dataset caches from `nec prepare`, comma-separated", true);
  cli.option("-o", "SPM.model", "", "the piece model to write", true);
  cli.option("--vocab-size", "N", "1000", "most pieces, <pad> and <unk> included (fewer when the captions hold fewer)");
  cli.option("--model-type", "TYPE", "bpe", "bpe, unigram, word or char");
  cli.flag("--force", "replace -o when it exists");
  cli.example("nec text train-tokenizer --data cache/ -o runs/spm.model");
  if (!cli.parse(argc, argv)) return 0;
  const std::string out = cli.value("-o");
  if (std::filesystem::exists(out) && !cli.is_set("--force")) {
    throw InputError(out, 0, "exists; pass --force to replace it");
  }
  text::PieceTrainOptions options;
  options.vocab_size = cli.integer("--vocab-size");
  options.model_type = cli.value("--model-type");
  try {
    options.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  std::vector<std::string> sentences;
  std::map<std::string, int> word_counts;
  for (const std::string& dir : cli.list("--data")) {
    const DatasetCache cache = read_cache(dir);
    for (const CacheClip& clip : cache.clips) {
      if (clip.split != Split::Train) continue;
      for (const std::string& caption : clip.captions) {
        const std::string text = text::normalize_caption(caption);
        if (text.empty()) continue;
        sentences.push_back(text);
        for (const std::string& word : text::caption_words(text)) ++word_counts[word];
      }
    }
  }
  if (sentences.empty()) throw InputError(cli.value("--data"), 0, "the train split holds no captions");
  text::train_piece_model(sentences, options, out);
  const text::PieceModel model = text::PieceModel::load(out);

  // How whole the corpus words stay: what GloVe-initialised piece embeddings need.
  size_t whole_words = 0, occurrences = 0, whole_occurrences = 0, pieces = 0, longest = 0;
  for (const auto& [word, count] : word_counts) {
    const bool whole = model.encode(word).size() == 1;
    whole_words += whole ? 1 : 0;
    occurrences += static_cast<size_t>(count);
    whole_occurrences += whole ? static_cast<size_t>(count) : 0;
  }
  for (const std::string& sentence : sentences) {
    const size_t n = model.encode(sentence).size();
    pieces += n;
    longest = std::max(longest, n);
  }
  const std::set<std::string> distinct(sentences.begin(), sentences.end());
  fmt::print("wrote {}: {} pieces ({}) from {} captions ({} distinct) of the train split\n", out, model.vocab_size(),
             options.model_type, sentences.size(), distinct.size());
  fmt::print("words: {} distinct, {} of them one piece ({:.1f} % of all word occurrences); pieces per caption: mean "
             "{:.1f}, most {}\n",
             word_counts.size(), whole_words, 100.0 * whole_occurrences / std::max<size_t>(occurrences, 1),
             static_cast<double>(pieces) / sentences.size(), longest);
  return 0;
}

int run_pieces(int argc, char** argv) {
  CommandLine cli("nec text pieces",
                  "Show how a caption is read: its normalized text, its pieces and their ids, and the text the ids "
                  "decode to.");
  cli.positional("CAPTION", "the caption, quoted");
  cli.option("--model", "SPM.model", "", "the piece model (`nec text train-tokenizer`)", true);
  cli.example("nec text pieces \"A hound sprints, 3 times!\" --model runs/spm.model");
  if (!cli.parse(argc, argv)) return 0;
  const std::string text = text::checked_caption(cli.positional_value("CAPTION"), "CAPTION");
  const text::PieceModel model = text::PieceModel::load(cli.value("--model"));
  const std::vector<int> ids = model.encode(text);
  std::string pieces, numbers;
  for (const int id : ids) {
    pieces += (pieces.empty() ? "" : " ") + model.piece(id);
    numbers += (numbers.empty() ? "" : " ") + std::to_string(id);
  }
  fmt::print("normalized  {}\npieces      {}\nids         {}\ndecoded     {}\n", text, pieces, numbers, model.decode(ids));
  return 0;
}

}  // namespace nec::app

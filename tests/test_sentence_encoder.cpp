// The sentence encoder (text/sentence_encoder.h) against the package's own
// runner under node (tests/sentence_encoder/reference.mjs) on the sentences of
// tests/data/sentence_encoder_sentences.txt: the same piece ids and the same
// sentence vector (cosine >= 0.9999) for every one; and what it refuses.
// scripts/test.sh installs both halves (scripts/setup_sentence_encoder.sh and
// npm ci in tests/sentence_encoder); without node's half the comparison skips.
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/text/sentence_encoder.h"

#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace nec::text {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

const std::string kSource = NEC_SOURCE_DIR;
const std::string kSentences = kSource + "/tests/data/sentence_encoder_sentences.txt";
const std::string kReference = kSource + "/tests/sentence_encoder";

const SentenceEncoder& encoder() {
  static const SentenceEncoder loaded(default_sentence_encoder_dir());
  return loaded;
}

std::vector<std::string> sentences() {
  std::vector<std::string> out;
  std::istringstream lines(read_file(kSentences));
  for (std::string line; std::getline(lines, line);) out.push_back(line);
  return out;
}

double cosine(const at::Tensor& a, const at::Tensor& b) {
  return (a.to(torch::kFloat64) * b.to(torch::kFloat64)).sum().item<double>() /
         (a.to(torch::kFloat64).norm().item<double>() * b.to(torch::kFloat64).norm().item<double>());
}

TEST(SentenceEncoder, TheGraphIsReadAsItIs) {
  const SentenceEncoder& e = encoder();
  EXPECT_EQ(e->dim(), 512);
  EXPECT_EQ(e->max_pieces(), 128);
  EXPECT_EQ(e->pieces().size(), 8000);
  ASSERT_EQ(e->layers().size(), 2u);
  EXPECT_EQ(e->layers()[0].heads, 4);
  EXPECT_EQ(e->layers()[0].head_dim, 64);
  EXPECT_TRUE(e->layers()[0].projected_residual);  // 256 wide in, 512 out
  EXPECT_EQ(e->layers()[1].head_dim, 128);
  EXPECT_FALSE(e->layers()[1].projected_residual);
  EXPECT_NEAR(e->layers()[1].query_scale, 1.0 / std::sqrt(128.0), 1e-7);
}

TEST(SentenceEncoder, MatchesThePackagesRunner) {
  if (std::system("node --version > /dev/null 2>&1") != 0 || !fs::exists(kReference + "/node_modules/@energetic-ai/embeddings")) {
    // scripts/test.sh installs them; CI (NEC_REQUIRE_DOWNLOADS=1, set by .ci/run) must not pass without them.
    if (std::getenv("NEC_REQUIRE_DOWNLOADS") != nullptr) FAIL() << "node or the reference packages are missing";
    GTEST_SKIP() << "node or the reference packages are missing: npm ci --prefix tests/sentence_encoder";
  }
  const TempDir dir;
  const std::string out = dir / "reference.jsonl";
  ASSERT_EQ(std::system(("node " + kReference + "/reference.mjs " + kSentences + " > " + out + " 2> " + (dir / "node.log")).c_str()), 0)
      << read_file(dir / "node.log");
  const std::vector<std::string> texts = sentences();
  std::istringstream lines(read_file(out));
  std::vector<nlohmann::json> reference;
  for (std::string line; std::getline(lines, line);) reference.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(reference.size(), texts.size());
  ASSERT_GE(texts.size(), 100u);

  const SentenceEncoding all = encoder()->encode(texts);  // one batch: padding must not reach any sentence
  double smallest = 1.0;
  std::string worst;
  for (size_t i = 0; i < texts.size(); ++i) {
    ASSERT_EQ(reference[i]["text"].get<std::string>(), texts[i]);
    EXPECT_EQ(encoder()->pieces().encode(texts[i]), reference[i]["ids"].get<std::vector<int>>()) << texts[i];
    ASSERT_FALSE(reference[i]["embedding"].is_null()) << texts[i] << ": " << reference[i].value("error", "");
    const at::Tensor expected = torch::tensor(reference[i]["embedding"].get<std::vector<float>>());
    const double alone = cosine(encoder()->encode({texts[i]}).sentence[0], expected);
    const double batched = cosine(all.sentence[static_cast<int64_t>(i)], expected);
    EXPECT_GE(alone, 0.9999) << texts[i];
    EXPECT_GE(batched, 0.9999) << texts[i];
    if (std::min(alone, batched) < smallest) {
      smallest = std::min(alone, batched);
      worst = texts[i];
    }
  }
  std::printf("smallest cosine against the runner over %zu sentences: 1 - %.2e (\"%s\")\n", texts.size(), 1.0 - smallest,
              worst.c_str());
}

TEST(SentenceEncoder, FeaturesAndMaskFollowThePieces) {
  const SentenceEncoding out = encoder()->encode({"a dog trots to the left", "hello"});
  const int64_t long_count = static_cast<int64_t>(encoder()->pieces().encode("a dog trots to the left").size());
  ASSERT_EQ(out.features.sizes(), (at::IntArrayRef{2, long_count, 512}));
  EXPECT_EQ(out.mask.sum(1)[0].item<int64_t>(), long_count);
  const int64_t short_count = static_cast<int64_t>(encoder()->pieces().encode("hello").size());
  ASSERT_LT(short_count, long_count);
  EXPECT_EQ(out.mask.sum(1)[1].item<int64_t>(), short_count);
  EXPECT_GT(out.features[1].slice(0, 0, short_count).abs().min().item<float>(), 0.0f);
  EXPECT_EQ(out.features[1].slice(0, short_count, long_count).abs().max().item<float>(), 0.0f);  // zero at padding
  EXPECT_NEAR(out.sentence.norm(2, 1)[0].item<float>(), 1.0f, 1e-5);
  // A long sentence is cut to the graph's 128 pieces, as the runner's graph does.
  std::string many;
  for (int i = 0; i < 200; ++i) many += "dog ";
  const SentenceEncoding cut = encoder()->encode({many});
  EXPECT_EQ(cut.mask.size(1), 128);
  EXPECT_TRUE(cut.mask.all().item<bool>());
}

// The package's shards fill whole pages and are mapped; the same weights cut into shards of odd sizes are
// read instead, and must give the same sentences bit for bit.
TEST(SentenceEncoder, ShardsOfAnySizeHoldTheSameWeights) {
  const TempDir dir;
  const std::string source = default_sentence_encoder_dir();
  fs::copy_file(source + "/vocab.json", dir / "vocab.json");
  nlohmann::json model = nlohmann::json::parse(read_file(source + "/model.json"));
  std::string weights;
  for (const auto& shard : model["weightsManifest"][0]["paths"]) weights += read_file(source + "/" + shard.get<std::string>());
  const size_t cut[] = {0, 4097, 4097 + 3 * 1000 * 1000 + 6, weights.size()};
  nlohmann::json paths = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) {
    const std::string name = "odd-shard" + std::to_string(i + 1);
    write_file_atomic(dir / name, weights.substr(cut[i], cut[i + 1] - cut[i]));
    paths.push_back(name);
  }
  model["weightsManifest"][0]["paths"] = paths;
  write_file_atomic(dir / "model.json", model.dump());
  const SentenceEncoder read_in(dir.path().string());
  const std::vector<std::string> texts = {"a dog trots to the left", "somebody greets the crowd"};
  const SentenceEncoding expected = encoder()->encode(texts);
  const SentenceEncoding got = read_in->encode(texts);
  EXPECT_TRUE(torch::equal(got.sentence, expected.sentence));
  EXPECT_TRUE(torch::equal(got.features, expected.features));
}

TEST(SentenceEncoder, AnEmptySentenceIsRefused) {
  try {
    encoder()->encode({"a dog", ""});
    ADD_FAILURE() << "an empty sentence was encoded";
  } catch (const InputError& e) {
    EXPECT_TRUE(testing::contains(e.what(), "sentence 2 is empty")) << e.what();
  }
}

TEST(SentenceEncoder, MissingOrDamagedFilesNameTheFileAndTheSetupCommand) {
  const TempDir dir;
  const auto expect_refused = [&](const std::string& file) {
    try {
      SentenceEncoder broken(dir.path().string());
      ADD_FAILURE() << "loaded";
    } catch (const InputError& e) {
      EXPECT_TRUE(testing::contains(e.what(), file)) << e.what();
      EXPECT_TRUE(testing::contains(e.what(), "setup_sentence_encoder.sh")) << e.what();
    }
  };
  expect_refused("vocab.json");
  fs::copy_file(default_sentence_encoder_dir() + "/vocab.json", dir / "vocab.json");
  expect_refused("model.json");
  fs::copy_file(default_sentence_encoder_dir() + "/model.json", dir / "model.json");
  expect_refused("group1-shard1of7");
  for (const auto& entry : fs::directory_iterator(default_sentence_encoder_dir())) {
    if (entry.path().filename().string().rfind("group1-shard", 0) == 0) fs::copy_file(entry.path(), dir / entry.path().filename().string());
  }
  fs::resize_file(dir / "group1-shard7of7", 1000);  // truncated
  expect_refused("model.json");
}

}  // namespace
}  // namespace nec::text

// Corpus loading for `nec prepare`: discovery, dataset names, captions,
// segmentation of long takes, and unreadable files.
#include "nec/motion/bvh.h"
#include "nec/corpus/corpus.h"
#include "nec/motion/error.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace nec {
namespace {

namespace fs = std::filesystem;

class Corpus : public ::testing::Test {
 protected:
  // A random rig with `seconds` of motion at 30 fps, written as BVH.
  std::string write_clip(const std::string& relative, double seconds, unsigned seed) {
    std::mt19937 rng(seed);
    const Skeleton s = testing::random_skeleton(rng, 8);
    Motion m = Motion::rest(s, static_cast<int>(seconds * 30), 30.0);
    for (int t = 0; t < m.frame_count; ++t) {
      m.rotation(t, 1) = axis_rotation(0, 10.0 * std::sin(0.2 * t));
      m.translation(t, 0) = Vec3(0.0, 2.0, 0.0);
    }
    const std::string path = dir_ / relative;
    fs::create_directories(fs::path(path).parent_path());
    write_bvh(path, s, m);
    return path;
  }

  testing::TempDir dir_;
};

TEST_F(Corpus, FindsFilesAndNamesDatasets) {
  write_clip("rigs/a.bvh", 1, 1);
  write_clip("rigs/sub/b.BVH", 1, 2);
  dir_.write("rigs/notes.txt", "not a clip");
  const auto files = find_corpus_files({dir_ / "rigs", "mine=" + (dir_ / "rigs/a.bvh")});
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].dataset, "rigs");
  EXPECT_EQ(files[1].dataset, "rigs");
  EXPECT_EQ(files[2].dataset, "mine");
  EXPECT_THROW(find_corpus_files({dir_ / "missing"}), InputError);
  fs::create_directories(dir_.path() / "empty");
  EXPECT_THROW(find_corpus_files({dir_ / "empty"}), InputError);
}

TEST_F(Corpus, SidecarCaptionsBadFilesAndSegmentation) {
  const std::string captioned = write_clip("rigs/walk.bvh", 2, 3);
  dir_.write("rigs/walk.txt", "a thing waves\nsomething waves an arm\n");
  const std::string long_take = write_clip("rigs/long.bvh", 30, 4);
  dir_.write("rigs/broken.bvh", "HIERARCHY\nROOT A\n{\n");
  CorpusOptions options;
  options.threads = 2;
  const CorpusResult result = load_corpus(find_corpus_files({dir_ / "rigs"}), options);
  ASSERT_EQ(result.files.size(), 3u);
  // Sorted: broken, long, walk.
  EXPECT_NE(result.files[0].error.find("broken.bvh:"), std::string::npos) << result.files[0].error;
  EXPECT_EQ(result.files[0].clips, 0);
  EXPECT_TRUE(result.files[1].error.empty()) << result.files[1].error;
  EXPECT_GE(result.files[1].segments, 5);  // 30 s in clips of at most 6 s
  EXPECT_EQ(result.files[1].clips, result.files[1].segments);
  EXPECT_EQ(result.files[2].clips, 1);
  int frames = 0;
  for (const CacheEntry& e : result.entries) {
    if (e.source == captioned) {
      EXPECT_EQ(e.captions, (std::vector<std::string>{"a thing waves", "something waves an arm"}));
    }
    if (e.source == long_take) {
      ASSERT_TRUE(e.prepared.report.accepted()) << e.prepared.report.rejection;
      EXPECT_FALSE(e.captions.empty());
      EXPECT_EQ(e.prepared.clip.motion.translation(0, 0).x(), 0.0);  // each clip starts at the origin
      frames += e.prepared.clip.motion.frame_count;
    }
  }
  // The segments cover the take.
  EXPECT_NEAR(frames, 900, 900 * 0.01);
  // The whole result makes a cache.
  const DatasetCache cache = build_cache(result.entries, CacheOptions{});
  EXPECT_EQ(cache.rejected.size(), 1u);
  EXPECT_EQ(cache.clip_count(), 1 + result.files[1].clips);
}

}  // namespace
}  // namespace nec

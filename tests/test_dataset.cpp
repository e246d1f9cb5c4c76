// Dataset cache: write/read round trip, checks on damaged caches, skeleton
// dedupe, atomic replacement, splits (deterministic, held-out skeletons, one
// split per source file) and the load time of 1,000 clips.
#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/motion/kinematics.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <set>

namespace nec {
namespace {

using testing::TempDir;

namespace fs = std::filesystem;


std::vector<std::string> canonical_of(const Skeleton& s) {
  std::vector<std::string> out;
  for (const std::string& name : s.names) out.push_back("canonical " + name);
  return out;
}

CacheEntry make_entry(std::mt19937& rng, const Skeleton& skeleton, int frames, std::string source, std::string dataset,
                      std::vector<std::string> captions = {}) {
  std::uniform_real_distribution<double> uniform(0.5, 2.0);
  CacheEntry e;
  e.prepared.clip = Clip{skeleton, testing::random_motion(rng, skeleton, frames), {}};
  e.prepared.canonical_names = canonical_of(skeleton);
  e.prepared.normalization.scale = uniform(rng);
  e.prepared.normalization.rotation = testing::random_rotation(rng);
  e.prepared.normalization.origin = Vec3(uniform(rng), -uniform(rng), uniform(rng) / 3.0);
  e.prepared.normalization.source_fps = 120.0;
  e.prepared.report.file = source;
  e.prepared.report.changes = {"scaled by 1/" + std::to_string(e.prepared.normalization.scale), "resampled 120 -> 30 fps"};
  e.source = std::move(source);
  e.dataset = std::move(dataset);
  e.captions = std::move(captions);
  return e;
}

// Runs `f` and checks it throws InputError whose message holds every one of `parts`.
void expect_input_error(const std::function<void()>& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown";
  } catch (const InputError& e) {
    const std::string message = e.what();
    for (const std::string& part : parts) EXPECT_NE(message.find(part), std::string::npos) << "message: " << message;
  }
}

std::vector<CacheEntry> small_corpus(std::mt19937& rng) {
  const Skeleton human = testing::random_skeleton(rng, 7);
  const Skeleton dog = testing::random_skeleton(rng, 11);
  std::vector<CacheEntry> entries;
  entries.push_back(make_entry(rng, human, 12, "bandai/walk_001.bvh", "bandai", {"a person walks"}));
  entries.push_back(make_entry(rng, human, 5, "bandai/run_002.bvh", "bandai", {"a person runs", "someone jogs", "läuft – schnell"}));
  entries.push_back(make_entry(rng, dog, 20, "dog/D1_001.bvh", "dog", {"a dog trots"}));
  entries.back().source_frame = 0;
  entries.push_back(make_entry(rng, dog, 17, "dog/D1_001.bvh", "dog", {}));
  entries.back().source_frame = 20;
  entries.push_back(make_entry(rng, dog, 1, "dog/D1_002.bvh", "dog", {"a dog sits"}));
  CacheEntry rejected = make_entry(rng, dog, 3, "dog/broken.bvh", "dog");
  rejected.prepared.report.rejection = "bone 'Tail' is 0.9 of the diameter";
  entries.push_back(rejected);
  return entries;
}

TEST(DatasetCache, WriteReadRoundTripIsExact) {
  std::mt19937 rng(1);
  const std::vector<CacheEntry> entries = small_corpus(rng);
  CacheOptions options;
  options.split.seed = 1234567890123ull;
  options.split.val_fraction = 0.25;
  options.split.test_fraction = 0.25;
  options.preprocess.up = UpAxis::Z;
  options.preprocess.max_bone_ratio = 0.55;
  const TempDir dir;
  write_cache(dir / "cache", entries, options);
  const DatasetCache cache = read_cache(dir / "cache");

  EXPECT_EQ(cache.fps, 30.0);
  EXPECT_EQ(cache.options.split.seed, options.split.seed);
  EXPECT_EQ(cache.options.split.val_fraction, 0.25);
  EXPECT_EQ(cache.options.preprocess.up, UpAxis::Z);
  EXPECT_EQ(cache.options.preprocess.max_bone_ratio, 0.55);
  ASSERT_EQ(cache.clip_count(), 5);
  ASSERT_EQ(cache.skeletons.size(), 2u);
  ASSERT_EQ(cache.rejected.size(), 1u);
  EXPECT_EQ(cache.rejected[0].source, "dog/broken.bvh");
  EXPECT_EQ(cache.rejected[0].reason, "bone 'Tail' is 0.9 of the diameter");
  EXPECT_EQ(cache.rejected[0].report, entries[5].prepared.report.changes);

  double worst_position = 0.0;
  for (int i = 0; i < cache.clip_count(); ++i) {
    const CacheEntry& e = entries[i];
    const CacheClip& c = cache.clips[i];
    EXPECT_EQ(c.source, e.source);
    EXPECT_EQ(c.dataset, e.dataset);
    EXPECT_EQ(c.captions, e.captions);
    EXPECT_EQ(c.report, e.prepared.report.changes);
    EXPECT_EQ(c.frame_count, e.prepared.clip.motion.frame_count);
    EXPECT_EQ(c.source_frame, e.source_frame);
    EXPECT_EQ(c.normalization.scale, e.prepared.normalization.scale);
    EXPECT_EQ(c.normalization.rotation.coeffs(), e.prepared.normalization.rotation.coeffs());
    EXPECT_EQ(c.normalization.origin, e.prepared.normalization.origin);
    EXPECT_EQ(c.normalization.source_fps, 120.0);

    // Features bit-exact.
    const Features expected = encode_features(e.prepared.clip.skeleton, e.prepared.clip.motion);
    const Features got = cache.features(i);
    ASSERT_EQ(got.data.size(), expected.data.size());
    EXPECT_EQ(std::memcmp(got.data.data(), expected.data.data(), got.data.size() * sizeof(float)), 0) << "clip " << i;
    EXPECT_EQ(got.start_xz, expected.start_xz);

    // Skeleton exact.
    const CachedSkeleton& stored = cache.skeleton_of(i);
    const Skeleton& s = e.prepared.clip.skeleton;
    EXPECT_EQ(stored.skeleton.names, s.names);
    EXPECT_EQ(stored.skeleton.parents, s.parents);
    EXPECT_EQ(stored.skeleton.offsets, s.offsets);
    ASSERT_EQ(stored.skeleton.channels.size(), s.channels.size());
    for (size_t j = 0; j < s.channels.size(); ++j) EXPECT_TRUE(stored.skeleton.channels[j] == s.channels[j]);
    ASSERT_EQ(stored.skeleton.end_sites.size(), s.end_sites.size());
    for (size_t k = 0; k < s.end_sites.size(); ++k) {
      EXPECT_EQ(stored.skeleton.end_sites[k].parent, s.end_sites[k].parent);
      EXPECT_EQ(stored.skeleton.end_sites[k].offset, s.end_sites[k].offset);
    }
    EXPECT_EQ(stored.canonical_names, e.prepared.canonical_names);

    // The decoded clip is the motion (float features: small position error).
    const Clip decoded = cache.clip(i);
    const Pose a = forward_kinematics(s, e.prepared.clip.motion);
    const Pose b = forward_kinematics(decoded.skeleton, decoded.motion);
    worst_position = std::max(worst_position, testing::max_position_difference(a.positions, b.positions) / s.diameter());
  }
  std::printf("decoded clip vs source: max position difference / diameter = %.3g\n", worst_position);
  EXPECT_LT(worst_position, 1e-4);

  // Ids: unique, "#n" only for sources with several clips.
  EXPECT_EQ(cache.clips[0].id, "bandai/walk_001.bvh");
  EXPECT_EQ(cache.clips[2].id, "dog/D1_001.bvh#0");
  EXPECT_EQ(cache.clips[3].id, "dog/D1_001.bvh#1");

  // Saving what was read gives the same files.
  save_cache(cache, dir / "again");
  for (const char* name : {"manifest.json", "features.f32", "skeletons.bin"}) {
    EXPECT_EQ(read_file(dir / ("cache/" + std::string(name))), read_file(dir / ("again/" + std::string(name)))) << name;
  }
}

TEST(DatasetCache, IdenticalSkeletonsAreStoredOnce) {
  std::mt19937 rng(2);
  const Skeleton a = testing::random_skeleton(rng, 6);
  const Skeleton b = testing::random_skeleton(rng, 9);
  std::vector<CacheEntry> entries;
  for (int i = 0; i < 6; ++i) entries.push_back(make_entry(rng, i % 2 ? a : b, 4, "bandai/" + std::to_string(i) + ".bvh", "bandai"));
  // Same tree, different canonical names: a different skeleton.
  entries.push_back(make_entry(rng, a, 4, "zoo/x.bvh", "zoo"));
  entries.back().prepared.canonical_names[1] = "left wing";
  // Same tree, an offset differs by rounding (1e-6 diameters): the same skeleton.
  Skeleton rounded = a;
  rounded.offsets[2].x() += 1e-6 * a.diameter();
  entries.push_back(make_entry(rng, rounded, 4, "bandai/rounded.bvh", "bandai"));
  // Same tree, an offset differs by 1e-3 diameters: a different skeleton.
  Skeleton nudged = a;
  nudged.offsets[2].x() += 1e-3 * a.diameter();
  entries.push_back(make_entry(rng, nudged, 4, "zoo/spider.bvh", "zoo"));
  entries.back().skeleton_name = "spider";

  const TempDir dir;
  write_cache(dir / "cache", entries, CacheOptions{});
  const DatasetCache cache = read_cache(dir / "cache");
  ASSERT_EQ(cache.skeletons.size(), 4u);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(cache.clips[i].skeleton, i % 2 ? 1 : 0) << i;
  EXPECT_EQ(cache.clips[7].skeleton, 1);
  EXPECT_EQ(cache.skeletons[0].name, "bandai");
  EXPECT_EQ(cache.skeletons[1].name, "bandai-2");
  EXPECT_EQ(cache.skeletons[2].name, "zoo");
  EXPECT_EQ(cache.skeletons[3].name, "spider");
  std::set<std::string> hashes;
  for (const CachedSkeleton& s : cache.skeletons) {
    EXPECT_EQ(s.hash.size(), 16u);
    hashes.insert(s.hash);
  }
  EXPECT_EQ(hashes.size(), 4u);
  EXPECT_EQ(cache.max_joint_count(), 9);
}

TEST(DatasetCache, VersionMismatchFailsWithHint) {
  std::mt19937 rng(3);
  const TempDir dir;
  write_cache(dir / "cache", small_corpus(rng), CacheOptions{});
  const std::string manifest = read_file(dir / "cache/manifest.json");
  const std::string key = "\"version\": " + std::to_string(kDatasetFormatVersion) + ",";
  const size_t at = manifest.find(key);
  ASSERT_NE(at, std::string::npos);
  std::string changed = manifest;
  changed.replace(at, key.size(), "\"version\": 99,");
  write_file_atomic(dir / "cache/manifest.json", changed);
  expect_input_error([&] { read_cache(dir / "cache"); }, {"manifest.json", "version 99", "re-run nec prepare"});

  changed = manifest;
  changed.replace(manifest.find("nec-dataset"), 11, "nec-tokens!");
  write_file_atomic(dir / "cache/manifest.json", changed);
  expect_input_error([&] { read_cache(dir / "cache"); }, {"manifest.json", "not a dataset manifest", "re-run nec prepare"});

  write_file_atomic(dir / "cache/manifest.json", manifest.substr(0, manifest.size() / 2));
  expect_input_error([&] { read_cache(dir / "cache"); }, {"manifest.json", "not valid JSON", "re-run nec prepare"});

  changed = manifest;
  changed.replace(manifest.find("\"frames\""), 8, "\"framez\"");
  write_file_atomic(dir / "cache/manifest.json", changed);
  expect_input_error([&] { read_cache(dir / "cache"); }, {"manifest.json", "malformed manifest", "re-run nec prepare"});
}

TEST(DatasetCache, DamagedArrayFilesFailWithHint) {
  std::mt19937 rng(4);
  const TempDir dir;
  write_cache(dir / "cache", small_corpus(rng), CacheOptions{});
  const std::string features = read_file(dir / "cache/features.f32");
  const std::string skeletons = read_file(dir / "cache/skeletons.bin");

  write_file_atomic(dir / "cache/features.f32", features.substr(0, features.size() - 4));
  expect_input_error([&] { read_cache(dir / "cache"); }, {"features.f32", "bytes, the manifest expects", "re-run nec prepare"});
  write_file_atomic(dir / "cache/features.f32", features + "abcd");
  expect_input_error([&] { read_cache(dir / "cache"); }, {"features.f32", "re-run nec prepare"});
  fs::remove(dir / "cache/features.f32");
  expect_input_error([&] { read_cache(dir / "cache"); }, {"features.f32", "re-run nec prepare"});
  write_file_atomic(dir / "cache/features.f32", features);
  EXPECT_NO_THROW(read_cache(dir / "cache"));

  write_file_atomic(dir / "cache/skeletons.bin", skeletons.substr(0, skeletons.size() - 1));
  expect_input_error([&] { read_cache(dir / "cache"); }, {"skeletons.bin", "re-run nec prepare"});
  std::string flipped = skeletons;
  flipped[skeletons.size() - 3] ^= 0x40;
  write_file_atomic(dir / "cache/skeletons.bin", flipped);
  expect_input_error([&] { read_cache(dir / "cache"); }, {"skeletons.bin", "hash", "re-run nec prepare"});
  std::string bad_version = skeletons;
  bad_version[8] = 7;
  write_file_atomic(dir / "cache/skeletons.bin", bad_version);
  expect_input_error([&] { read_cache(dir / "cache"); }, {"skeletons.bin", "version 7", "re-run nec prepare"});

  expect_input_error([&] { read_cache(dir / "nowhere"); }, {"nowhere", "nec prepare"});
  fs::create_directories(dir / "empty");
  expect_input_error([&] { read_cache(dir / "empty"); }, {"no manifest.json", "nec prepare"});
}

TEST(DatasetCache, WritesAreAtomic) {
  std::mt19937 rng(5);
  const std::vector<CacheEntry> entries = small_corpus(rng);
  const TempDir dir;
  // A directory that is not a cache is never replaced.
  fs::create_directories(dir / "photos");
  write_file_atomic(dir / "photos/cat.jpg", "meow");
  expect_input_error([&] { write_cache(dir / "photos", entries, CacheOptions{}); }, {"photos", "not a dataset cache"});
  EXPECT_EQ(read_file(dir / "photos/cat.jpg"), "meow");

  // A cache is replaced as a whole.
  write_cache(dir / "cache", entries, CacheOptions{});
  std::vector<CacheEntry> fewer(entries.begin(), entries.begin() + 2);
  write_cache(dir / "cache/", fewer, CacheOptions{});
  EXPECT_EQ(read_cache(dir / "cache").clip_count(), 2);

  // A failure in the middle of a write leaves the old cache and no debris.
  DatasetCache broken = build_cache(entries, CacheOptions{});
  broken.clips.back().skeleton = 99;
  EXPECT_THROW(save_cache(broken, dir / "cache"), std::invalid_argument);
  EXPECT_EQ(read_cache(dir / "cache").clip_count(), 2);
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir.path())) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"cache", "photos"}));
}

TEST(DatasetCache, BadEntriesAreRejected) {
  std::mt19937 rng(6);
  const Skeleton s = testing::random_skeleton(rng, 5);
  std::vector<CacheEntry> entries{make_entry(rng, s, 4, "a.bvh", "x")};
  entries[0].prepared.clip.motion.fps = 60.0;
  EXPECT_THROW(build_cache(entries, CacheOptions{}), std::invalid_argument);
  entries = {make_entry(rng, s, 4, "a.bvh", "x")};
  entries[0].prepared.canonical_names.pop_back();
  EXPECT_THROW(build_cache(entries, CacheOptions{}), std::invalid_argument);
  entries = {make_entry(rng, s, 4, "a.bvh", "x"), make_entry(rng, s, 4, "b.bvh", "x")};
  entries[0].id = entries[1].id = "same";
  EXPECT_THROW(build_cache(entries, CacheOptions{}), std::invalid_argument);
  CacheOptions bad;
  bad.split.val_fraction = 0.7;
  bad.split.test_fraction = 0.5;
  EXPECT_THROW(bad.split.validate(), std::invalid_argument);
}

TEST(DatasetSplits, WildcardMatch) {
  EXPECT_TRUE(wildcard_match("spider*", "spider-2"));
  EXPECT_TRUE(wildcard_match("*der*", "spider"));
  EXPECT_TRUE(wildcard_match("d?g", "dog"));
  EXPECT_TRUE(wildcard_match("*", ""));
  EXPECT_TRUE(wildcard_match("a*b*c", "aXbYbZc"));
  EXPECT_FALSE(wildcard_match("spider", "spider-2"));
  EXPECT_FALSE(wildcard_match("d?g", "dg"));
  EXPECT_FALSE(wildcard_match("a*b*c", "aXbYbZ"));
}

// 60 sources of 1 to 4 clips on 3 skeletons, and 4 long takes cut into 25 clips each.
std::vector<CacheEntry> split_corpus(std::mt19937& rng) {
  const Skeleton human = testing::random_skeleton(rng, 5);
  const Skeleton spider = testing::random_skeleton(rng, 9);
  const Skeleton dog = testing::random_skeleton(rng, 7);
  std::vector<CacheEntry> entries;
  for (int file = 0; file < 60; ++file) {
    const int clips = 1 + file % 4;
    const bool is_spider = file % 10 == 3;
    for (int k = 0; k < clips; ++k) {
      entries.push_back(make_entry(rng, is_spider ? spider : human, 2, (is_spider ? "zoo/spider_" : "bandai/take_") + std::to_string(file) + ".bvh",
                                   is_spider ? "zoo" : "bandai"));
      if (is_spider) entries.back().skeleton_name = "spider";
    }
  }
  for (int take = 0; take < 4; ++take) {
    for (int k = 0; k < 25; ++k) {
      entries.push_back(make_entry(rng, dog, 2, "dog/D1_00" + std::to_string(take) + ".bvh", "dog"));
      entries.back().source_frame = 2 * k;
    }
  }
  return entries;
}

std::map<std::string, Split> split_by_id(const DatasetCache& cache) {
  std::map<std::string, Split> out;
  for (const CacheClip& c : cache.clips) out[c.id] = c.split;
  return out;
}

TEST(DatasetSplits, DeterministicAndIndependentOfEntryOrder) {
  std::mt19937 rng(7);
  std::vector<CacheEntry> entries = split_corpus(rng);
  CacheOptions options;
  options.split.val_fraction = 0.1;
  options.split.test_fraction = 0.2;
  options.split.seed = 11;
  const DatasetCache first = build_cache(entries, options);
  const DatasetCache again = build_cache(entries, options);
  EXPECT_EQ(split_by_id(first), split_by_id(again));
  EXPECT_EQ(assign_splits(first, options.split), assign_splits(again, options.split));

  // Reordering whole sources keeps every clip's split (ids stay the same).
  std::vector<CacheEntry> reversed;
  for (size_t end = entries.size(); end > 0;) {
    size_t begin = end - 1;
    while (begin > 0 && entries[begin - 1].source == entries[end - 1].source) --begin;
    reversed.insert(reversed.end(), entries.begin() + begin, entries.begin() + end);
    end = begin;
  }
  EXPECT_EQ(split_by_id(build_cache(reversed, options)), split_by_id(first));

  // The folder the files were named from does not matter: only the path below
  // the folder that holds a dataset's files does.
  std::vector<CacheEntry> elsewhere = entries;
  for (CacheEntry& e : elsewhere) {
    e.source = "/home/someone/corpus/" + e.source;
    if (!e.id.empty()) e.id = "/home/someone/corpus/" + e.id;
  }
  const DatasetCache moved = build_cache(elsewhere, options);
  ASSERT_EQ(moved.clip_count(), first.clip_count());
  for (int i = 0; i < first.clip_count(); ++i) EXPECT_EQ(moved.clips[i].split, first.clips[i].split) << i;

  // Another seed, another split.
  options.split.seed = 12;
  EXPECT_NE(split_by_id(build_cache(entries, options)), split_by_id(first));

  // Fractions are met to within the size of one source (25 clips).
  const double total = first.clip_count();
  const double test = first.clips_in(Split::Test).size(), val = first.clips_in(Split::Val).size();
  std::printf("clips %.0f: test %.0f (target %.1f), val %.0f (target %.1f)\n", total, test, 0.2 * total, val, 0.1 * total);
  EXPECT_NEAR(test, 0.2 * total, 25.0 / 2);
  EXPECT_NEAR(val, 0.1 * total, 25.0 / 2);
  EXPECT_GT(first.clips_in(Split::Train).size(), 0.6 * total);
}

TEST(DatasetSplits, NoSourceFileInTwoSplits) {
  std::mt19937 rng(8);
  const std::vector<CacheEntry> entries = split_corpus(rng);
  for (uint64_t seed = 0; seed < 20; ++seed) {
    CacheOptions options;
    options.split.seed = seed;
    options.split.val_fraction = 0.15;
    options.split.test_fraction = 0.15;
    const DatasetCache cache = build_cache(entries, options);
    std::map<std::string, std::set<Split>> splits_of_source;
    for (const CacheClip& c : cache.clips) splits_of_source[c.source].insert(c.split);
    for (const auto& [source, splits] : splits_of_source) EXPECT_EQ(splits.size(), 1u) << source << " seed " << seed;
    EXPECT_FALSE(cache.clips_in(Split::Val).empty()) << seed;
    EXPECT_FALSE(cache.clips_in(Split::Test).empty()) << seed;
  }
}

TEST(DatasetSplits, HeldOutSkeletonsAreAllInTest) {
  std::mt19937 rng(9);
  std::vector<CacheEntry> entries = split_corpus(rng);
  CacheOptions options;
  options.split.held_out_skeletons = {"spi*"};
  DatasetCache cache = build_cache(entries, options);
  const std::vector<int> held = held_out_skeletons(cache, options.split);
  ASSERT_EQ(held.size(), 1u);
  EXPECT_EQ(cache.skeletons[held[0]].name, "spider");
  int spider_clips = 0;
  for (const CacheClip& c : cache.clips) {
    if (c.skeleton == held[0]) {
      EXPECT_EQ(c.split, Split::Test) << c.id;
      ++spider_clips;
    }
  }
  EXPECT_EQ(spider_clips, std::count_if(entries.begin(), entries.end(), [](const CacheEntry& e) { return e.dataset == "zoo"; }));
  EXPECT_FALSE(cache.clips_in(Split::Train).empty());

  // By hash, and by dataset.
  options.split.held_out_skeletons = {cache.skeletons[held[0]].hash};
  EXPECT_EQ(held_out_skeletons(cache, options.split), held);
  options.split.held_out_skeletons = {};
  options.split.held_out_datasets = {"dog"};
  cache = build_cache(entries, options);
  for (const CacheClip& c : cache.clips) {
    if (c.dataset == "dog") {
      EXPECT_EQ(c.split, Split::Test) << c.id;
    }
  }

  // Every clip of a held-out skeleton goes to test, whichever dataset it came
  // from: one zoo clip on the human rig holds out all the bandai clips.
  entries.push_back(make_entry(rng, entries[0].prepared.clip.skeleton, 2, "zoo/human_like.bvh", "zoo"));
  options.split.held_out_datasets = {"zoo"};
  cache = build_cache(entries, options);
  for (const CacheClip& c : cache.clips) {
    if (c.dataset != "dog") {
      EXPECT_EQ(c.split, Split::Test) << c.id;
    } else {
      EXPECT_NE(c.split, Split::Test) << c.id;
    }
  }

  // A name that matches nothing is an error, not a silent no-op.
  options.split.held_out_datasets = {};
  options.split.held_out_skeletons = {"spidr"};
  EXPECT_THROW(build_cache(entries, options), std::invalid_argument);
}

}  // namespace
}  // namespace nec

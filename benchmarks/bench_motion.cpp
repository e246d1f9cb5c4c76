// Throughput of the motion core on real files: BVH parsing (MB/s of text) and
// forward kinematics (joint-frames/s, one thread), and reading a 1,000-clip dataset cache.
//
//   bench_motion [benchmark flags] [FILE.bvh ...]
//
// Without files it uses the MANN dog takes in ../shared/data/mann_dog, or the
// Debian CMU files when that folder is absent. Every benchmark warms up, runs
// 5 repetitions of at least 1 s of wall-clock time and reports mean, median,
// stddev and cv; scripts/bench.sh reads the medians. 1 MB = 10^6 bytes in bench.sh's table (Google Benchmark's
// own console line uses 1024-based units).
#include "nec/motion/bvh.h"
#include "nec/corpus/dataset.h"
#include "nec/motion/files.h"
#include "nec/motion/kinematics.h"
#include "nec/corpus/preprocess.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Corpus {
  std::vector<std::string> paths;
  std::vector<std::string> texts;  // file contents, read once
  std::vector<nec::Clip> clips;    // parsed once, for FK
  size_t bytes = 0;
  size_t joint_frames = 0;
};

Corpus& corpus() {
  static Corpus instance;
  return instance;
}

std::vector<std::string> bvh_files_in(const std::string& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return out;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".bvh") out.push_back(entry.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void load_corpus(std::vector<std::string> paths) {
  if (paths.empty()) paths = bvh_files_in(std::string(NEC_SHARED_DATA_DIR) + "/mann_dog");
  if (paths.empty()) paths = bvh_files_in(NEC_CMU_BVH_DIR);
  Corpus& c = corpus();
  for (const std::string& path : paths) {
    c.paths.push_back(path);
    c.texts.push_back(nec::read_file(path));
    c.clips.push_back(nec::parse_bvh(c.texts.back(), path));
    c.bytes += c.texts.back().size();
    c.joint_frames += static_cast<size_t>(c.clips.back().motion.frame_count) * c.clips.back().motion.joint_count;
  }
  std::fprintf(stderr, "bench_motion: %zu files, %.1f MB, %zu joint-frames\n", c.paths.size(), c.bytes / 1e6,
               c.joint_frames);
}

// Parses every file of the corpus once per iteration.
void BM_ParseBvh(benchmark::State& state) {
  const Corpus& c = corpus();
  for (auto _ : state) {
    for (size_t i = 0; i < c.texts.size(); ++i) {
      nec::Clip clip = nec::parse_bvh(c.texts[i], c.paths[i]);
      benchmark::DoNotOptimize(clip.motion.rotations.data());
    }
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * c.bytes));
  state.counters["files"] = static_cast<double>(c.texts.size());
}

// Global rotations and positions (nec::forward_kinematics) for every clip.
void BM_ForwardKinematics(benchmark::State& state) {
  const Corpus& c = corpus();
  for (auto _ : state) {
    for (const nec::Clip& clip : c.clips) {
      const nec::Pose pose = nec::forward_kinematics(clip.skeleton, clip.motion);
      benchmark::DoNotOptimize(pose.positions.data());
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * c.joint_frames));
}

// Positions only into reused storage (nec::joint_positions), as training batches use it.
void BM_JointPositions(benchmark::State& state) {
  const Corpus& c = corpus();
  std::vector<nec::Vec3> positions;
  for (auto _ : state) {
    for (const nec::Clip& clip : c.clips) {
      nec::joint_positions(clip.skeleton, clip.motion, positions);
      benchmark::DoNotOptimize(positions.data());
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * c.joint_frames));
}

// A dataset cache of 1,000 clips (the corpus's clips, preprocessed, 90 frames each, repeated), written once.
const std::string& thousand_clip_cache() {
  static const std::string dir = [] {
    const Corpus& c = corpus();
    std::vector<nec::PreparedClip> prepared;
    for (const nec::Clip& clip : c.clips) {
      nec::PreparedClip p = nec::preprocess(clip, "bench");
      if (!p.report.accepted()) continue;
      if (p.clip.motion.frame_count > 90) p.clip.motion = p.clip.motion.slice(0, 90);
      prepared.push_back(std::move(p));
    }
    if (prepared.empty()) throw std::runtime_error("no corpus clip survives preprocessing");
    std::vector<nec::CacheEntry> entries;
    for (int i = 0; i < 1000; ++i) {
      nec::CacheEntry e;
      e.prepared = prepared[static_cast<size_t>(i) % prepared.size()];
      e.source = "corpus/take_" + std::to_string(i / 3) + ".bvh";
      e.dataset = "bench";
      e.captions = {"caption one of clip " + std::to_string(i), "caption two"};
      entries.push_back(std::move(e));
    }
    const std::string out = (std::filesystem::temp_directory_path() / "nec_bench_thousand_clips").string();
    nec::write_cache(out, entries, nec::CacheOptions{});
    return out;
  }();
  return dir;
}

// read_cache of 1,000 clips plus one pass over every feature (the memory map's
// pages are faulted in at read time, not hidden in the first use).
void BM_ReadCache(benchmark::State& state) {
  const std::string& dir = thousand_clip_cache();
  size_t floats = 0;
  for (auto _ : state) {
    const nec::DatasetCache cache = nec::read_cache(dir);
    float sum = 0.0f;
    for (size_t i = 0; i < cache.feature_data.size(); i += 16) sum += cache.feature_data[i];
    benchmark::DoNotOptimize(sum);
    floats = cache.feature_data.size();
  }
  state.counters["clips"] = 1000;
  state.counters["feature_MB"] = static_cast<double>(floats * sizeof(float)) / (1 << 20);
}

void register_all() {
  for (auto* b : {benchmark::RegisterBenchmark("BM_ParseBvh", BM_ParseBvh),
                  benchmark::RegisterBenchmark("BM_ForwardKinematics", BM_ForwardKinematics),
                  benchmark::RegisterBenchmark("BM_JointPositions", BM_JointPositions),
                  benchmark::RegisterBenchmark("BM_ReadCache", BM_ReadCache)}) {
    b->Unit(benchmark::kMillisecond)
        ->UseRealTime()  // wall clock, as the three.js peer measures
        ->MinWarmUpTime(0.5)
        ->MinTime(1.0)
        ->Repetitions(5)
        ->ReportAggregatesOnly(true);
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);  // removes the --benchmark_* flags it knows
  try {
    load_corpus(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_motion: %s\n", e.what());
    return 1;
  }
  if (corpus().paths.empty()) {
    std::fprintf(stderr, "bench_motion: no BVH files (give paths, or install assimp-testmodels)\n");
    return 1;
  }
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

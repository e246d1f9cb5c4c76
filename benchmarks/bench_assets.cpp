// Import rate of rigged assets through assimp against nec's BVH reader on the
// same motion (BVH files exported by Blender as FBX and GLB), and the time of
// writing a motion onto an asset as GLB.
//
//   bench_assets DIR     # DIR holds STEM.bvh, STEM.fbx and STEM.glb per motion (scripts/bench.sh assets)
//
// Rates count the BVH's frames (assets are sampled at the BVH's rate) and the
// bytes of each format's own files. Every benchmark runs 5 repetitions of at
// least 1 s; scripts/bench.sh reads the medians.
#include "nec/assets/asset_reader.h"
#include "nec/assets/asset_writer.h"
#include "nec/motion/bvh.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

struct Motion {
  std::string stem;  // DIR/STEM
  double fps = 30;
  size_t frames = 0;
};

std::vector<Motion>& motions() {
  static std::vector<Motion> all;
  return all;
}

void read_all(benchmark::State& state, const std::string& ext) {
  size_t bytes = 0, frames = 0;
  for (const Motion& m : motions()) {
    bytes += fs::file_size(m.stem + ext);
    frames += m.frames;
  }
  for (auto _ : state) {
    for (const Motion& m : motions()) {
      nec::ClipReadOptions options;
      options.fps = m.fps;
      benchmark::DoNotOptimize(nec::read_clips(m.stem + ext, options));
    }
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * bytes));
  state.counters["frames_per_s"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ReadBvh(benchmark::State& state) { read_all(state, ".bvh"); }
void BM_ReadFbx(benchmark::State& state) { read_all(state, ".fbx"); }
void BM_ReadGlb(benchmark::State& state) { read_all(state, ".glb"); }

// A motion of the asset's own skeleton written back onto it: GLB bytes in memory.
void BM_WriteGlbOntoAsset(benchmark::State& state, const std::string& asset) {
  const nec::Clip clip = nec::read_clip(asset);
  for (auto _ : state) benchmark::DoNotOptimize(nec::assets::animation_onto_asset(clip, asset, "bench"));
  state.counters["frames"] = clip.motion.frame_count;
  state.counters["joints"] = clip.skeleton.joint_count();
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (argc != 2) {
    std::fprintf(stderr, "usage: bench_assets [benchmark flags] DIR (STEM.bvh, STEM.fbx, STEM.glb per motion)\n");
    return 2;
  }
  nec::assets::register_asset_formats();
  for (const auto& entry : fs::directory_iterator(argv[1])) {
    if (entry.path().extension() != ".bvh") continue;
    const std::string stem = (entry.path().parent_path() / entry.path().stem()).string();
    if (!fs::exists(stem + ".fbx") || !fs::exists(stem + ".glb")) continue;
    const nec::Clip clip = nec::read_bvh(entry.path().string());
    motions().push_back({stem, clip.motion.fps, static_cast<size_t>(clip.motion.frame_count)});
  }
  std::sort(motions().begin(), motions().end(), [](const Motion& a, const Motion& b) { return a.stem < b.stem; });
  if (motions().empty()) {
    std::fprintf(stderr, "bench_assets: no STEM.bvh with STEM.fbx and STEM.glb in %s\n", argv[1]);
    return 1;
  }
  for (auto* bm : {benchmark::RegisterBenchmark("BM_ReadBvh", BM_ReadBvh),
                   benchmark::RegisterBenchmark("BM_ReadFbx", BM_ReadFbx),
                   benchmark::RegisterBenchmark("BM_ReadGlb", BM_ReadGlb)}) {
    bm->Unit(benchmark::kMillisecond)->MinTime(1.0)->Repetitions(5)->ReportAggregatesOnly(true);
  }
  const std::string models = "/usr/share/assimp/models";
  for (const char* asset : {"/X/Testwuson.X", "/X/BCN_Epileptic.X"}) {
    if (!fs::exists(models + asset)) continue;
    benchmark::RegisterBenchmark(("BM_WriteGlbOntoAsset" + std::string(asset)).c_str(), BM_WriteGlbOntoAsset,
                                 models + asset)
        ->Unit(benchmark::kMillisecond)->MinTime(1.0)->Repetitions(5)->ReportAggregatesOnly(true);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

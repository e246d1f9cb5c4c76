#!/usr/bin/env bash
# Builds bench_motion (build-bench/, Release) and times it next to the three.js
# peer on the same BVH files, then prints a Markdown table of medians.
#   scripts/bench.sh                 # MANN dog takes (../shared/data/mann_dog), else the Debian CMU files
#   scripts/bench.sh FILE.bvh ...    # these files
# Goals: nec parses >= 10x faster than three.js BVHLoader.parse; FK >= 20 M joint-frames/s.
# Raw results: build-bench/bench_motion.json, build-bench/peer_threejs.json.
set -euo pipefail
cd "$(dirname "$0")/.."

source scripts/lib.sh
ensure_packages bench cmake ninja-build libeigen3-dev nlohmann-json3-dev libfmt-dev libbenchmark-dev nodejs npm assimp-testmodels
ensure_three

cmake -S . -B build-bench -G Ninja -DCMAKE_BUILD_TYPE=Release -DNEC_BUILD_BENCHMARKS=ON -DNEC_BUILD_TESTS=OFF >/dev/null
cmake --build build-bench --target bench_motion

files=("$@")
if [ ${#files[@]} -eq 0 ]; then
  mapfile -t files < <(find ../shared/data/mann_dog -maxdepth 1 -name '*.bvh' 2>/dev/null | sort)
fi
if [ ${#files[@]} -eq 0 ]; then
  mapfile -t files < <(find /usr/share/assimp/models/BVH -maxdepth 1 -name '*.bvh' | sort)
fi
echo "bench: ${#files[@]} files ($(cat "${files[@]}" | wc -c) bytes), first: ${files[0]}"

build-bench/benchmarks/bench_motion --benchmark_format=console \
  --benchmark_out=build-bench/bench_motion.json --benchmark_out_format=json "${files[@]}"
node benchmarks/peer_threejs.mjs --warmup 2 --repeat 5 "${files[@]}" | tee build-bench/peer_threejs.json

node - build-bench/bench_motion.json build-bench/peer_threejs.json <<'JS'
const fs = require('fs');
const [nec, peer] = process.argv.slice(2).map((p) => JSON.parse(fs.readFileSync(p, 'utf8')));
const stat = (name, aggregate, field) => {
  const row = nec.benchmarks.find((b) => b.run_name.startsWith(name) && b.aggregate_name === aggregate);
  return row[field];
};
const parse = stat('BM_ParseBvh', 'median', 'bytes_per_second') / 1e6;
const parseCv = stat('BM_ParseBvh', 'cv', 'bytes_per_second') * 100;
const fk = stat('BM_ForwardKinematics', 'median', 'items_per_second');
const fkCv = stat('BM_ForwardKinematics', 'cv', 'items_per_second') * 100;
const positions = stat('BM_JointPositions', 'median', 'items_per_second');
const ratio = parse / peer.median_mb_per_s;
const verdict = (ok) => (ok ? 'met' : 'MISSED');
console.log(`
Median of 5 repetitions; ${peer.files} files, ${peer.megabytes.toFixed(1)} MB; 1 MB = 10^6 bytes; one thread.

| metric | value | spread | goal |
|---|---:|---|---|
| nec parse (MB/s) | ${parse.toFixed(1)} | cv ${parseCv.toFixed(1)} % | |
| three.js ${peer.node} BVHLoader.parse (MB/s) | ${peer.median_mb_per_s.toFixed(1)} | ${peer.min_mb_per_s.toFixed(1)}–${peer.max_mb_per_s.toFixed(1)} | |
| ratio nec / three.js | ${ratio.toFixed(1)}x | | >= 10x: ${verdict(ratio >= 10)} |
| FK, forward_kinematics (M joint-frames/s) | ${(fk / 1e6).toFixed(1)} | cv ${fkCv.toFixed(1)} % | >= 20: ${verdict(fk >= 20e6)} |
| FK, joint_positions only (M joint-frames/s) | ${(positions / 1e6).toFixed(1)} | | |
`);
JS

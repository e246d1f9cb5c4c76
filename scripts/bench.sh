#!/usr/bin/env bash
# Builds the Google Benchmark programs (build-bench/, Release), times them next
# to their peers in the same run and prints Markdown tables of medians.
#   scripts/bench.sh                 # both sections below
#   scripts/bench.sh motion [FILE.bvh ...]
#       BVH parsing and FK against three.js BVHLoader.parse, on the MANN dog
#       takes (../shared/data/mann_dog), else the Debian CMU files, or FILEs.
#       Goals: nec parses >= 10x faster than three.js; FK >= 20 M joint-frames/s.
#   scripts/bench.sh tat
#       Tokenizer training step (configs/tat_cpu.json, 22 and 100 joints, 1 and
#       2 threads) against the same step in PyTorch / Python
#       (benchmarks/peer_tat_step.py, Debian python3-torch), whole-clip encode /
#       decode throughput and the step's peak memory. Goal: the C++ step takes
#       at most the Python step's time. About 3 minutes on an idle 2-core machine.
# Raw results: build-bench/bench_motion.json, build-bench/peer_threejs.json,
# build-bench/bench_tat.json, build-bench/peer_tat_step.json (NEC_BENCH_BUILD=DIR
# builds and writes in DIR instead of build-bench).
set -euo pipefail
cd "$(dirname "$0")/.."

section=all
case "${1:-}" in
  motion | tat) section=$1; shift ;;
esac
if [ "$section" = tat ] && [ $# -gt 0 ]; then
  echo "bench.sh: 'tat' takes no arguments" >&2
  exit 2
fi
build=${NEC_BENCH_BUILD:-build-bench}
python=/usr/bin/python3  # Debian's, the one python3-torch installs into

source scripts/lib.sh
ensure_packages bench cmake ninja-build libeigen3-dev nlohmann-json3-dev libfmt-dev libbenchmark-dev
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DNEC_BUILD_BENCHMARKS=ON -DNEC_BUILD_TESTS=OFF >/dev/null

bench_motion() {
  ensure_packages bench nodejs npm assimp-testmodels
  ensure_three
  cmake --build "$build" --target bench_motion
  local files=("$@")
  if [ ${#files[@]} -eq 0 ]; then
    mapfile -t files < <(find ../shared/data/mann_dog -maxdepth 1 -name '*.bvh' 2>/dev/null | sort)
  fi
  if [ ${#files[@]} -eq 0 ]; then
    mapfile -t files < <(find /usr/share/assimp/models/BVH -maxdepth 1 -name '*.bvh' | sort)
  fi
  echo "bench: ${#files[@]} files ($(cat "${files[@]}" | wc -c) bytes), first: ${files[0]}"

  "$build"/benchmarks/bench_motion --benchmark_format=console \
    --benchmark_out="$build"/bench_motion.json --benchmark_out_format=json "${files[@]}"
  node benchmarks/peer_threejs.mjs --warmup 2 --repeat 5 "${files[@]}" | tee "$build"/peer_threejs.json

  node - "$build"/bench_motion.json "$build"/peer_threejs.json <<'JS'
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
}

bench_tat() {
  ensure_packages bench python3-torch
  cmake --build "$build" --target bench_tat
  local load_before
  load_before=$(cut -d' ' -f1-3 /proc/loadavg)
  # The two training-step measurements back to back, the clip benchmarks after.
  "$build"/benchmarks/bench_tat --benchmark_filter=TrainStep --benchmark_format=console \
    --benchmark_out="$build"/bench_tat.json --benchmark_out_format=json
  local parameters
  parameters=$("$python" -c 'import json, sys
rows = json.load(open(sys.argv[1]))["benchmarks"]
print(int(next(r["parameters"] for r in rows if r["name"].startswith("BM_TatTrainStep"))))' "$build"/bench_tat.json)
  "$python" benchmarks/peer_tat_step.py --expect-parameters "$parameters" >"$build"/peer_tat_step.json
  "$build"/benchmarks/bench_tat --benchmark_filter=Clip --benchmark_format=console \
    --benchmark_out="$build"/bench_tat_clip.json --benchmark_out_format=json
  local load_after
  load_after=$(cut -d' ' -f1-3 /proc/loadavg)

  "$python" - "$build"/bench_tat.json "$build"/bench_tat_clip.json "$build"/peer_tat_step.json \
    "$load_before" "$load_after" <<'PY'
import json, re, sys

step_json, clip_json, peer_json, load_before, load_after = sys.argv[1:]
rows = json.load(open(step_json))["benchmarks"] + json.load(open(clip_json))["benchmarks"]
peer = json.load(open(peer_json))

def nec_row(name, joints, threads, aggregate):
    pattern = rf"{name}/joints:{joints}/threads:{threads}/"
    for row in rows:
        if row.get("aggregate_name") == aggregate and re.match(pattern, row["name"]):
            return row
    raise SystemExit(f"bench.sh: no {aggregate} of {pattern} in bench_tat's output")

def peer_run(joints, threads):
    return next(r for r in peer["runs"] if r["joints"] == joints and r["threads"] == threads)

def verdict(ok):
    return "met" if ok else "MISSED"

settings = [(joints, threads) for joints in (22, 100) for threads in (1, 2)]
step = nec_row("BM_TatTrainStep", 22, 1, "median")
print(f"""
Tokenizer, configs/tat_cpu.json ({step['parameters']:.0f} parameters in both), batch of 16 x 64 frames;
median of {peer['repetitions']} repetitions, wall clock; torch {peer['torch']} (Debian), Python {peer['python']};
load average (1, 5, 15 min) {load_before} before, {load_after} after.

| training step | C++ (ms) | min-max | Python (ms) | min-max | C++ / Python | goal <= 1 |
|---|---:|---|---:|---|---:|---|""")
for joints, threads in settings:
    median, low, high = (nec_row("BM_TatTrainStep", joints, threads, aggregate)["real_time"]
                         for aggregate in ("median", "min", "max"))
    run = peer_run(joints, threads)
    ratio = median / run["median_ms"]
    print(f"| {joints} joints, {threads} thread{'s' if threads > 1 else ''} | {median:.1f} | {low:.1f}-{high:.1f} | "
          f"{run['median_ms']:.1f} | {run['min_ms']:.1f}-{run['max_ms']:.1f} | {ratio:.2f} | {verdict(ratio <= 1.0)} |")

print("""
| same step, same inputs | C++ | Python | relative difference |
|---|---:|---:|---:|""")
worst = 0.0
for joints in (22, 100):
    row, run = nec_row("BM_TatTrainStep", joints, 1, "median"), peer_run(joints, 1)
    for key in ("loss_step0", "loss_step1"):
        difference = abs(row[key] - run[key]) / max(abs(run[key]), 1e-12)
        worst = max(worst, difference)
        print(f"| {joints} joints, {key.replace('_', ' ')} | {row[key]:.6f} | {run[key]:.6f} | {difference:.1e} |")
    print(f"| {joints} joints, peak RSS of a step above its start (MiB) | {row['step_peak_MiB']:.1f} | "
          f"{run['step_peak_MiB']:.1f} | |")
    print(f"| {joints} joints, process peak RSS during it (MiB) | {row['rss_peak_MiB']:.1f} | "
          f"{run['rss_peak_MiB']:.1f} | |")

print("""
| whole clip, 600 frames, C++ | frames/s, 1 thread | frames/s, 2 threads |
|---|---:|---:|""")
for name, label in (("BM_TatEncodeClip", "encode_clip"), ("BM_TatDecodeClip", "decode_clip")):
    for joints in (22, 100):
        rates = [nec_row(name, joints, threads, "median")["frames_per_s"] for threads in (1, 2)]
        print(f"| {label}, {joints} joints | {rates[0]:.0f} | {rates[1]:.0f} |")
print()
if worst > 1e-3:
    raise SystemExit(f"bench.sh: the Python peer's first losses differ from bench_tat's by {worst:.1e} "
                     "(relative): it is not the same computation")
PY
}

case "$section" in
  motion) bench_motion "$@" ;;
  tat) bench_tat ;;
  all) bench_motion "$@"; bench_tat ;;
esac

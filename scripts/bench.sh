#!/usr/bin/env bash
# Builds the Google Benchmark programs (build-bench/, Release), times them next
# to their peers in the same run and prints Markdown tables of medians.
#   scripts/bench.sh                 # every section below but assets
#   scripts/bench.sh motion [FILE.bvh ...]
#       BVH parsing and FK against three.js BVHLoader.parse, on the MANN dog
#       takes (../shared/data/mann_dog), else the Debian CMU files, or FILEs.
#       Goals: nec parses >= 20x faster than three.js (median ratio of 3 rounds in
#       which the two take turns); FK >= 20 M joint-frames/s.
#   scripts/bench.sh tat
#       Tokenizer training step (configs/tat_cpu.json, 22 and 100 joints, 1 and
#       2 threads) against the same step in PyTorch / Python
#       (benchmarks/peer_tat_step.py, Debian python3-torch), whole-clip encode /
#       decode throughput and the step's peak memory. About 4 minutes.
#   scripts/bench.sh evaluator
#       The text-motion evaluator (configs/evaluator_cpu.json): its training step
#       against benchmarks/peer_evaluator_step.py (22 and 100 joints, 1 and 2
#       threads); captions encoded per second, clips embedded per second (22 and
#       100 joints), and a retrieval query over a 10,000-clip index (goal: < 20 ms
#       on 2 cores).
#   scripts/bench.sh gpt
#       The GPT's training step against benchmarks/peer_gpt_step.py (1 and 2
#       threads); generation: a 4-s motion from text to BVH on disk with the
#       default GPT (one sample, goal < 0.5 s; 32 samples, goal < 3 s), and
#       sampled tokens per second with and without the KV cache at 4, 16 and 64 s.
#   scripts/bench.sh diffusion
#       The diffusion model's training steps (pose and motion stage, 22 and 100
#       joints, 1 and 2 threads) against benchmarks/peer_diffusion_step.py;
#       sampling (configs/diffusion_pose_cpu.json's denoiser, random weights): a
#       4-s motion by 10 DPM-Solver++ and by 50 DDIM steps with guidance, one sample (goal < 3 s on 2
#       cores) and a batch of 8, peak memory; and one layer's factorized
#       attention against full spatio-temporal attention for J = 20, 60, 140
#       joints and T = 60, 120, 240 frames. About 15 minutes.
#       Sampling runs with OpenMP's default wait policy (as nec runs) unless
#       OMP_WAIT_POLICY is set.
#   scripts/bench.sh steps
#       The four training steps above against their peers, nothing else.
#   Training steps: C++ and Python take turns in 2 rounds; goal: the C++ step
#   takes at most 0.7 of the Python step's wall-clock time (median); both sides'
#   first two losses must agree (they run the same computation on the same
#   inputs and weights); both run with nec's allocator policy and
#   OMP_WAIT_POLICY=passive unless set. The last round profiles one more step
#   per setting on both sides (benchmarks/train_step_support.h, peer_step.py):
#   op calls, time inside and outside ATen, the ops of largest self time.
#   scripts/bench.sh process
#       Commands as a user runs them, start to exit, median of 5 with a warm file
#       cache, and their peak RSS (benchmarks/process_times.py): nec generate with
#       the default GPT and with the default diffusion model (4-s motion onto the
#       31-joint CMU rig; goals <= 0.5 s and <= 2 s), nec retrieve on a built
#       index (goal <= 0.5 s), beside a program that only loads LibTorch
#       (benchmarks/torch_floor.cpp): the start-up no change inside nec removes.
#   scripts/bench.sh studio
#       nec serve as a script uses it (benchmarks/studio_latency.py): upload the 31-joint CMU rig, then request ->
#       done of ten 4-s GPT generations one at a time (goal: median <= 0.15 s) and of ten searches (goal <= 50 ms),
#       50 concurrent generate requests (all must finish), the studio's and its workers' memory before and after;
#       warm workers (the default) against --process-per-job in the same run.
#   scripts/bench.sh blender
#       The Blender add-on's Generate, from the press to the new action (benchmarks/blender_generate.py; installs
#       blender): models kept loaded in a nec worker (the default; goal: a later press <= 0.3 s) against a new nec
#       process per press, taking turns.
#   scripts/bench.sh assets
#       Rigged assets: reading FBX and GLB (assimp) against reading BVH, on the
#       Debian CMU files and a zoo dragon exported by Blender 3.4
#       (tests/interop/blender_export_assets.py; installs blender), frames/s and
#       MB/s; and writing a motion onto an asset as GLB (ms).
# Raw results in build-bench/: bench_motion.json, bench_motion_parse{1,2,3}.json, peer_threejs{1,2,3}.json,
# bench_NAME_step{1,2}.json and peer_NAME_step{1,2}.json (NAME: tat, evaluator, gpt, diffusion), profiles/,
# bench_tat_clip.json, bench_evaluator.json, bench_gpt.json, bench_diffusion.json, bench_assets.json,
# process_times.json
# (NEC_BENCH_BUILD=DIR builds and writes in DIR instead).
set -euo pipefail
cd "$(dirname "$0")/.."

section=all
case "${1:-}" in
  motion | tat | steps | evaluator | gpt | diffusion | process | assets) section=$1; shift ;;
esac
if [ "$section" != motion ] && [ "$section" != all ] && [ $# -gt 0 ]; then
  echo "bench.sh: '$section' takes no arguments" >&2
  exit 2
fi
build=${NEC_BENCH_BUILD:-build-bench}
python=/usr/bin/python3  # Debian's, the one python3-torch installs into
step_rounds=2            # turns of C++ and Python training-step runs
step_repetitions=3       # repetitions per program and round
motion_rounds=3          # turns of nec and three.js parsing runs

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

  "$build"/benchmarks/bench_motion --benchmark_filter='ForwardKinematics|JointPositions' --benchmark_format=console \
    --benchmark_out="$build"/bench_motion.json --benchmark_out_format=json "${files[@]}"
  # Parsing: nec and three.js take turns, round by round, so that the machine's slow and fast minutes fall on
  # both; each round gives a ratio.
  local round
  for round in $(seq 1 $motion_rounds); do
    "$build"/benchmarks/bench_motion --benchmark_filter=BM_ParseBvh --benchmark_out="$build"/bench_motion_parse$round.json \
      --benchmark_out_format=json "${files[@]}" >/dev/null
    node benchmarks/peer_threejs.mjs --warmup 2 --repeat 5 "${files[@]}" >"$build"/peer_threejs$round.json
  done

  node - "$build" "$motion_rounds" <<'JS'
const fs = require('fs');
const [build, rounds] = [process.argv[2], Number(process.argv[3])];
const read = (file) => JSON.parse(fs.readFileSync(`${build}/${file}`, 'utf8'));
// A missing row or a value that is not a finite number stops the table (it never prints NaN).
const stat = (nec, file, name, aggregate, field) => {
  const row = nec.benchmarks.find((b) => b.run_name.startsWith(name) && b.aggregate_name === aggregate);
  const value = row ? row[field] : undefined;
  if (!Number.isFinite(value)) throw new Error(`bench.sh: no finite ${field} of the ${aggregate} of ${name} in ${file}`);
  return value;
};
const median = (values) => [...values].sort((a, b) => a - b)[Math.floor(values.length / 2)];
const verdict = (ok) => (ok ? 'met' : 'MISSED');
const lines = [];
const ratios = [];
let peer;
for (let round = 1; round <= rounds; ++round) {
  const file = `bench_motion_parse${round}.json`;
  const nec = read(file);
  peer = read(`peer_threejs${round}.json`);
  for (const key of ['median_mb_per_s', 'min_mb_per_s', 'max_mb_per_s', 'megabytes']) {
    if (!Number.isFinite(peer[key])) throw new Error(`bench.sh: peer_threejs${round}.json has no finite ${key}`);
  }
  const parse = stat(nec, file, 'BM_ParseBvh', 'median', 'bytes_per_second') / 1e6;
  const cv = stat(nec, file, 'BM_ParseBvh', 'cv', 'bytes_per_second') * 100;
  const ratio = parse / peer.median_mb_per_s;
  ratios.push(ratio);
  lines.push(`| ${round} | ${parse.toFixed(1)} (cv ${cv.toFixed(1)} %) | ${peer.median_mb_per_s.toFixed(1)} ` +
             `(${peer.min_mb_per_s.toFixed(1)}–${peer.max_mb_per_s.toFixed(1)}) | ${ratio.toFixed(1)}x |`);
}
const fkRows = read('bench_motion.json');
const fk = stat(fkRows, 'bench_motion.json', 'BM_ForwardKinematics', 'median', 'items_per_second');
const fkCv = stat(fkRows, 'bench_motion.json', 'BM_ForwardKinematics', 'cv', 'items_per_second') * 100;
const positions = stat(fkRows, 'bench_motion.json', 'BM_JointPositions', 'median', 'items_per_second');
const lowest = Math.min(...ratios);
console.log(`
Median of 5 repetitions per round; ${peer.files} files, ${peer.megabytes.toFixed(1)} MB; 1 MB = 10^6 bytes; one thread.

| round | nec parse, MB/s | three.js ${peer.node} BVHLoader.parse, MB/s (min–max) | nec / three.js |
|---|---:|---:|---:|
${lines.join('\n')}

Ratio: median ${median(ratios).toFixed(1)}x (goal >= 20x: ${verdict(median(ratios) >= 20)}), lowest ${lowest.toFixed(1)}x.

| metric | value | spread | goal |
|---|---:|---|---|
| FK, forward_kinematics (M joint-frames/s) | ${(fk / 1e6).toFixed(1)} | cv ${fkCv.toFixed(1)} % | >= 20: ${verdict(fk >= 20e6)} |
| FK, joint_positions only (M joint-frames/s) | ${(positions / 1e6).toFixed(1)} | | |
`);
JS
}

# train_step_against_peer NAME FAMILY TITLE CONFIG...: the training step of bench_NAME's FAMILY benchmark
# against benchmarks/peer_NAME_step.py, both reading one snapshot of the CONFIG files (so that a change in
# configs/ meanwhile falls on neither), in $step_rounds turns; tables by benchmarks/train_step_report.py.
train_step_against_peer() {
  local name=$1 family=$2 title=$3 parameters="" round load_before load_after
  shift 3
  ensure_packages bench python3-torch
  cmake --build "$build" --target "bench_$name"
  local configs="$build/bench_${name}_configs"
  mkdir -p "$configs"
  cp "$@" "$configs"/
  # Idle OpenMP threads sleep instead of spinning: with spinning, two threads on
  # a 2-core machine that also runs anything else wait out whole time slices at
  # every parallel region (here 10x slower steps than one thread, both sides).
  local -x OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
  load_before=$(cut -d' ' -f1-3 /proc/loadavg)
  # C++ and Python take turns, so that a change in the machine's load between them falls on both.
  # The last round also profiles one more step per setting on both sides (after the timed ones).
  local profiles="$build/profiles" profile_nec=() profile_peer=()
  rm -rf "$profiles"
  for round in $(seq 1 "$step_rounds"); do
    if [ "$round" = "$step_rounds" ]; then
      profile_nec=(--profile_ops="$profiles")
      profile_peer=(--profile-ops "$profiles")
    fi
    "$build/benchmarks/bench_$name" --configs="$configs" --benchmark_filter="$family" \
      --benchmark_repetitions="$step_repetitions" --benchmark_format=console "${profile_nec[@]}" \
      --benchmark_out="$build/bench_${name}_step$round.json" --benchmark_out_format=json
    if [ -z "$parameters" ]; then
      parameters=$("$python" -c 'import json, sys
rows = json.load(open(sys.argv[1]))["benchmarks"]
print(int(next(r["parameters"] for r in rows if r["name"].startswith(sys.argv[2]))))' \
        "$build/bench_${name}_step$round.json" "$family")
    fi
    "$python" "benchmarks/peer_${name}_step.py" --configs "$configs" --expect-parameters "$parameters" \
      --repetitions "$step_repetitions" "${profile_peer[@]}" >"$build/peer_${name}_step$round.json"
  done
  load_after=$(cut -d' ' -f1-3 /proc/loadavg)
  local nec_files=() peer_files=()
  for round in $(seq 1 "$step_rounds"); do
    nec_files+=("$build/bench_${name}_step$round.json")
    peer_files+=("$build/peer_${name}_step$round.json")
  done
  "$python" benchmarks/train_step_report.py --family "$family" --title "$title" \
    --nec "${nec_files[@]}" --peer "${peer_files[@]}" \
    --load-before "$load_before" --load-after "$load_after" --wait-policy "$OMP_WAIT_POLICY"
  local profile setting
  for profile in "$profiles/${family}"_*.json; do
    setting=${profile#"$profiles/${family}_"}
    setting=${setting%.json}
    "$python" benchmarks/op_profile_report.py --title "$family, ${setting//_/ }" \
      "$profile" "$profiles/peer_${name}_step_$setting.json"
  done
}

tat_step() {
  train_step_against_peer tat BM_TatTrainStep "Tokenizer, configs/tat_cpu.json, batch of 16 x 64 frames" \
    configs/tat_cpu.json configs/owo_cpu.json
}

evaluator_step() {
  train_step_against_peer evaluator BM_EvaluatorTrainStep \
    "Evaluator, configs/evaluator_cpu.json, batch of 64 x 64 frames, synthetic use-lite captions" \
    configs/evaluator_cpu.json configs/owo_cpu.json
}

gpt_step() {
  train_step_against_peer gpt BM_GptTrainStep \
    "GPT, configs/gpt_cpu.json (codes of configs/tat_cpu.json), batch of 32 crops of up to 47 steps" \
    configs/gpt_cpu.json configs/tat_cpu.json configs/owo_cpu.json
}

diffusion_step() {
  train_step_against_peer diffusion BM_DiffusionTrainStep \
    "Diffusion, configs/diffusion_{pose,motion}_cpu.json (motion stage: batch of 4 x 120 frames; pose stage: 32 x 64)" \
    configs/diffusion_pose_cpu.json configs/diffusion_motion_cpu.json configs/owo_cpu.json
}

bench_tat() {
  tat_step
  OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive} "$build"/benchmarks/bench_tat --configs="$build"/bench_tat_configs \
    --benchmark_filter=Clip --benchmark_format=console \
    --benchmark_out="$build"/bench_tat_clip.json --benchmark_out_format=json
  "$python" - "$build"/bench_tat_clip.json <<'PY'
import sys
sys.path.insert(0, "benchmarks")
from bench_json import BenchRows
median = BenchRows(sys.argv[1]).median
print("""
| whole clip, 600 frames, C++ (median) | frames/s, 1 thread | frames/s, 2 threads |
|---|---:|---:|""")
for name, label in (("BM_TatEncodeClip", "encode_clip"), ("BM_TatDecodeClip", "decode_clip")):
    for joints in (22, 100):
        rates = [median(f"{name}/joints:{joints}/threads:{threads}", "frames_per_s") for threads in (1, 2)]
        print(f"| {label}, {joints} joints | {rates[0]:.0f} | {rates[1]:.0f} |")
print()
PY
}

bench_evaluator() {
  evaluator_step
  OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive} "$build"/benchmarks/bench_evaluator --benchmark_filter=-TrainStep \
    --benchmark_format=console \
    --benchmark_out="$build"/bench_evaluator.json --benchmark_out_format=json >/dev/null
  "$python" - "$build"/bench_evaluator.json <<'PY'
import sys
sys.path.insert(0, "benchmarks")
from bench_json import BenchRows
median = BenchRows(sys.argv[1]).median
print("""
| evaluator (configs/evaluator_cpu.json), median of 5 | 1 thread | 2 threads |
|---|---:|---:|""")
print("| captions encoded per second (batches of 32) | " +
      " | ".join(f"{median(f'BM_EncodeCaptions/threads:{t}', 'captions_per_s'):.0f}" for t in (1, 2)) + " |")
print("| the same by the pretrained sentence encoder (pieces, graph, sentence vectors) | " +
      " | ".join(f"{median(f'BM_EncodeSentences/threads:{t}', 'captions_per_s'):.0f}" for t in (1, 2)) + " |")
for joints in (22, 100):
    print(f"| clips embedded per second, {joints} joints, 120 frames (OwO + motion encoder) | " +
          " | ".join(f"{median(f'BM_EmbedMotions/joints:{joints}/threads:{t}', 'clips_per_s'):.1f}" for t in (1, 2)) + " |")
print("| retrieval query over 10,000 clips, ms (goal < 20 on 2 cores) | " +
      " | ".join(f"{median(f'BM_RetrievalQuery/threads:{t}/captions:0'):.2f}" for t in (1, 2)) + " |")
print("| the same blended with 3 captions a clip (nec retrieve's default), ms | " +
      " | ".join(f"{median(f'BM_RetrievalQuery/threads:{t}/captions:3'):.2f}" for t in (1, 2)) + " |")
print()
PY
}

bench_gpt() {
  gpt_step
  OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive} "$build"/benchmarks/bench_gpt --benchmark_filter=-TrainStep \
    --benchmark_format=console \
    --benchmark_out="$build"/bench_gpt.json --benchmark_out_format=json >/dev/null
  "$python" - "$build"/bench_gpt.json <<'PY'
import sys
sys.path.insert(0, "benchmarks")
from bench_json import BenchRows
median = BenchRows(sys.argv[1]).median
print("""
| generation, median of 5, 2 cores | value |
|---|---:|""")
for samples, goal in ((1, 500), (32, 3000)):
    print(f"| text to BVH, 4-s motion, {samples} sample(s), ms (goal < {goal}) | {median(f'BM_TextToBvh/samples:{samples}'):.0f} |")
print("""
| sampled tokens per second | 4 s | 16 s | 64 s |
|---|---:|---:|---:|""")
for cache, label in ((1, "KV cache"), (0, "no cache (window recomputed each step)")):
    print(f"| {label} | " + " | ".join(f"{median(f'BM_SampleTokens/seconds:{s}/cache:{cache}', 'tokens_per_s'):.0f}" for s in (4, 16, 64)) + " |")
print()
PY
}

bench_diffusion() {
  diffusion_step
  # Timed as `nec generate` runs: nec sets no OpenMP wait policy (the default lets a thread spin briefly
  # between the many small operations of a step); OMP_WAIT_POLICY=passive scripts/bench.sh diffusion times
  # the other.
  "$build"/benchmarks/bench_diffusion --benchmark_filter=-TrainStep --benchmark_format=console \
    --benchmark_out="$build"/bench_diffusion.json --benchmark_out_format=json >/dev/null
  "$python" - "$build"/bench_diffusion.json "${OMP_WAIT_POLICY:-default}" <<'PY'
import sys
sys.path.insert(0, "benchmarks")
from bench_json import BenchRows
median = BenchRows(sys.argv[1]).median
print(f"OMP_WAIT_POLICY={sys.argv[2]}")
print("""
| diffusion sampling, 4-s motion, 24 joints, guidance 2.5; median of 3, 2 cores | s | peak memory, MB |
|---|---:|---:|""")
for ddim50, sampling in ((0, "10 DPM-Solver++ steps (default)"), (1, "50 uniform DDIM steps")):
    for batch, label in ((1, "one sample (goal < 3 s)"), (8, "a batch of 8")):
        name = f"BM_Sample4s/batch:{batch}/ddim50:{ddim50}"
        print(f"| {sampling}, {label} | {median(name) / 1000:.2f} | {median(name, 'peak_rss_mb'):.0f} |")
print("""
| one attention layer, ms (factorized / full spatio-temporal = ratio) | T = 60 | T = 120 | T = 240 |
|---|---:|---:|---:|""")
for joints in (20, 60, 140):
    cells = []
    for frames in (60, 120, 240):
        f = median(f"BM_Attention/joints:{joints}/frames:{frames}/full:0")
        g = median(f"BM_Attention/joints:{joints}/frames:{frames}/full:1")
        cells.append(f"{f:.0f} / {g:.0f} = {f / g:.3f}")
    print(f"| J = {joints} | " + " | ".join(cells) + " |")
print()
PY
}

bench_process() {
  ensure_packages bench assimp-testmodels
  cmake --build "$build" --target nec torch_floor
  local nec="$build"/apps/nec data="$build"/process_data
  local rig=/usr/share/assimp/models/BVH/01_01.bvh
  rm -rf "$data"
  mkdir -p "$data"
  "$nec" zoo --out "$data"/zoo --creatures 12 --clips-per-creature 4 --seed 1 --quiet >/dev/null
  "$nec" prepare zoo="$data"/zoo -o "$data"/cache --quiet >/dev/null
  "$python" benchmarks/process_times.py --repeat 5 --json "$build"/process_times.json \
    --run "a program that only loads LibTorch (the floor)" "$build/benchmarks/torch_floor" \
    --run "nec generate, default GPT, 4-s motion, 31-joint CMU rig (goal <= 0.5 s)" \
    "$nec generate 'a person waves' --skeleton $rig --seconds 4 -o $data/gpt.bvh --force" \
    --run "nec generate, default diffusion model (10 DPM-Solver++ steps), the same (goal <= 2 s)" \
    "$nec generate 'a person waves' --skeleton $rig --seconds 4 --model models/default/diffusion -o $data/diffusion.bvh --force" \
    --run "nec generate, default diffusion model, 50 uniform DDIM steps (the sampling before 2026-12-07)" \
    "$nec generate 'a person waves' --skeleton $rig --seconds 4 --model models/default/diffusion --solver ddim --steps 50 --spacing uniform -o $data/diffusion50.bvh --force" \
    --run "nec retrieve, 48-clip index built (goal <= 0.5 s)" "$nec retrieve 'a dog walks forward' --db $data/cache"
}

bench_studio() {
  ensure_packages bench assimp-testmodels
  cmake --build "$build" --target nec
  local nec="$build"/apps/nec data="$build"/studio_data
  rm -rf "$data"
  mkdir -p "$data"
  "$nec" zoo --out "$data"/zoo --creatures 16 --clips-per-creature 4 --seed 5 --quiet >/dev/null
  "$nec" prepare zoo="$data"/zoo/seen -o "$data"/cache --quiet >/dev/null
  "$python" benchmarks/studio_latency.py --nec "$nec" --rig /usr/share/assimp/models/BVH/01_01.bvh --db "$data"/cache \
    --repeat 10 --concurrent 50 --json "$build"/studio_latency.json
}

bench_blender() {
  ensure_packages bench blender assimp-testmodels
  cmake --build "$build" --target nec
  mkdir -p "$build"/blender_tmp
  TMPDIR="$build"/blender_tmp blender -b --factory-startup --python-exit-code 1 --python benchmarks/blender_generate.py \
    -- "$build"/apps/nec 10 2>"$build"/blender_generate.log | grep '^|'
}

bench_assets() {
  ensure_packages bench blender assimp-testmodels
  cmake --build "$build" --target bench_assets nec
  local data="$build"/bench_assets_data
  rm -rf "$data"
  mkdir -p "$data"
  cp /usr/share/assimp/models/BVH/*.bvh "$data"/
  "$build"/apps/nec zoo --out "$data"/zoo --creatures 9 --clips-per-creature 1 --seconds 8 --seed 1 --quiet >/dev/null
  cp "$(find "$data"/zoo -name '*.bvh' -path '*dragon*' | sort | head -n 1)" "$data"/dragon.bvh
  blender -b --factory-startup --python-exit-code 1 --python tests/interop/blender_export_assets.py -- \
    "$data" "$data"/*.bvh >"$build"/bench_assets_blender.log 2>&1
  "$build"/benchmarks/bench_assets --benchmark_format=console \
    --benchmark_out="$build"/bench_assets.json --benchmark_out_format=json "$data" >/dev/null
  "$python" - "$build"/bench_assets.json "$data" <<'PY'
import os, sys
sys.path.insert(0, "benchmarks")
from bench_json import BenchRows, benchmark_name
rows = BenchRows(sys.argv[1])
median = rows.median
stems = sorted(f[:-4] for f in os.listdir(sys.argv[2]) if f.endswith(".bvh"))
print(f"""
Median of 5 repetitions, one thread; {len(stems)} motions ({", ".join(stems)}), each as BVH and as Blender 3.4's FBX
and GLB; frames are the BVH's (assets sampled at its rate); 1 MB = 10^6 bytes of each format's files.

| read | frames/s | MB/s | frames/s vs BVH |
|---|---:|---:|---:|""")
bvh = median("BM_ReadBvh", "frames_per_s")
for name, label in (("BM_ReadBvh", "BVH (nec's reader)"), ("BM_ReadFbx", "FBX (assimp + nec)"), ("BM_ReadGlb", "GLB (assimp + nec)")):
    fps = median(name, "frames_per_s")
    print(f"| {label} | {fps:,.0f} | {median(name, 'bytes_per_second') / 1e6:.1f} | {fps / bvh:.2f} |")
print("""
| write a motion onto an asset as GLB | joints | frames | ms |
|---|---:|---:|---:|""")
for r in rows.medians_of("BM_WriteGlbOntoAsset/"):
    asset = benchmark_name(r["run_name"])[len("BM_WriteGlbOntoAsset/"):]
    print(f"| {asset} | {rows.value(r, 'joints'):.0f} | {rows.value(r, 'frames'):.0f} | {rows.value(r, 'real_time'):.1f} |")
print()
PY
}

case "$section" in
  motion) bench_motion "$@" ;;
  assets) bench_assets ;;
  tat) bench_tat ;;
  steps) tat_step; evaluator_step; gpt_step; diffusion_step ;;
  evaluator) bench_evaluator ;;
  gpt) bench_gpt ;;
  diffusion) bench_diffusion ;;
  process) bench_process ;;
  studio) bench_studio ;;
  blender) bench_blender ;;
  all) bench_motion "$@"; bench_tat; bench_evaluator; bench_gpt; bench_diffusion; bench_process ;;
esac

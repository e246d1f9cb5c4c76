#!/usr/bin/env bash
# Data-parallel training speed: steps/s of `nec train tat` (configs/tat_cpu.json,
# 16 clips x 64 frames a step, no validation or checkpoints in between) as one
# process x 2 threads against 2 processes x 1 thread (--nproc 2), on zoo bipeds
# (~22 joints) and centipedes (~100 joints). Prints a Markdown table of the
# medians over the repeats, alternating the two modes.
#   scripts/bench_data_parallel.sh [STEPS] [REPEATS]     # defaults: 30 steps, 3 repeats
# Needs build/apps/nec (scripts/setup.sh). Work files in build/bench-data-parallel/.
set -euo pipefail
cd "$(dirname "$0")/.."

steps=${1:-30}
repeats=${2:-3}
nec=build/apps/nec
work=build/bench-data-parallel
[ -x "$nec" ] || { echo "bench_data_parallel: $nec is missing; run scripts/setup.sh" >&2; exit 1; }
rm -rf "$work"
mkdir -p "$work"

# The CPU config without mid-run validation or checkpoints: only training steps are timed.
python3 - configs/tat_cpu.json "$work/tat.json" <<'PY'
import json, sys
config = json.load(open(sys.argv[1]))
config.update(validate_every=0, checkpoint_every=0, log_every=10)
json.dump(config, open(sys.argv[2], "w"))
PY
cat > "$work/owo.json" <<'JSON'
{"encoder": {"name_dim": 0}, "data": {"held_out": []}, "names": false, "steps": 10, "log_every": 10,
 "validate_every": 0, "checkpoint_every": 0}
JSON

for plan in biped centipede; do
  "$nec" zoo --out "$work/zoo_$plan" --plans "$plan" --creatures 4 --clips-per-creature 8 --seconds 4 --seed 2 --quiet --force
  "$nec" prepare "zoo=$work/zoo_$plan/seen" --val 0 --test 0 -o "$work/cache_$plan" --quiet > /dev/null
done
"$nec" train owo --config "$work/owo.json" --data "$work/cache_biped" --out "$work/owo" --threads 2 > /dev/null

# steps/s of one run: the last progress line's rate (steps only, after loading and rendezvous).
rate() {
  "$nec" train tat --config "$work/tat.json" --data "$1" --owo "$work/owo" --out "$work/run" --force \
    --steps "$steps" "${@:2}" | grep "^step $steps/$steps" | sed -E 's/.*  ([0-9.e+-]+) steps\/s.*/\1/'
}

echo "| creatures | 1 process x 2 threads | 2 processes x 1 thread | ratio |"
echo "|---|---|---|---|"
for plan in biped centipede; do
  joints=$(for f in "$work/zoo_$plan/seen/"*/*_k01_*.bvh; do "$nec" info --json "$f"; echo; done | python3 -c '
import json, sys
counts = [json.loads(line)["joints"] for line in sys.stdin if line.strip()]
print(f"{min(counts)}-{max(counts)} joints")')
  one=() two=()
  for _ in $(seq "$repeats"); do
    one+=("$(rate "$work/cache_$plan" --threads 2)")
    two+=("$(rate "$work/cache_$plan" --threads 1 --nproc 2)")
  done
  python3 - "$plan" "$joints" "${one[*]}" "${two[*]}" <<'PY'
import statistics, sys
plan, joints, one, two = sys.argv[1], sys.argv[2], [float(x) for x in sys.argv[3].split()], [float(x) for x in sys.argv[4].split()]
a, b = statistics.median(one), statistics.median(two)
print(f"| {plan} {joints} | {a:.3g} steps/s ({min(one):.3g}-{max(one):.3g}) | {b:.3g} steps/s "
      f"({min(two):.3g}-{max(two):.3g}) | {b / a:.2f} |")
PY
done

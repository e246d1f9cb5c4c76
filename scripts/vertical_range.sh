#!/usr/bin/env bash
# How much of the real clips' vertical motion comes back: for the zoo clips of actions that move the body up
# or down (jump, sit, lie_down, take_off), the range of the root's height (max - min over the clip) of a motion
# made from each clip, divided by the real clip's; median and quartiles per action.
#   scripts/vertical_range.sh EVAL_OUT [TOKENIZER]
# EVAL_OUT: a folder scripts/eval_generation.sh wrote (clips.tsv, generated/): the generated motions.
# TOKENIZER: also the tokenizer's reconstructions (`nec transfer` of each clip onto itself, --free-height
# --free-feet so that no correction moves the root), written to EVAL_OUT/reconstructed/.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ]; then
  echo "usage: scripts/vertical_range.sh EVAL_OUT [TOKENIZER]" >&2
  exit 2
fi
out=$1 tokenizer=${2:-}
nec=${NEC:-build/apps/nec}
if [ -n "$tokenizer" ]; then
  mkdir -p "$out/reconstructed"
  count=0
  while IFS=$'\t' read -r dataset source seconds _; do
    count=$((count + 1))
    case "$source" in *_jump.bvh|*_sit.bvh|*_lie_down.bvh|*_take_off.bvh) ;; *) continue ;; esac
    target="$out/reconstructed/$(printf %04d "$count").bvh"
    rm -f "$target"
    "$nec" transfer "$source" --to "$source" --model "$tokenizer" --free-height --free-feet -o "$target" > /dev/null
  done < "$out/clips.tsv"
fi
python3 - "$out" <<'PY'
import glob, os, statistics, sys
out = sys.argv[1]

def root_heights(path):
    lines = open(path).read().split("\n")
    motion = lines.index("MOTION")
    # The root's channels come first; the zoo's files are Y-up with Xposition Yposition Zposition.
    return [float(line.split()[1]) for line in lines[motion + 3:] if line.strip()]

def span(path):
    heights = root_heights(path)
    return max(heights) - min(heights)

clips = [line.rstrip("\n").split("\t") for line in open(os.path.join(out, "clips.tsv"))]
ratios = {}
for index, (dataset, source, *_) in enumerate(clips, 1):
    action = next((a for a in ("jump", "sit", "lie_down", "take_off") if source.endswith("_" + a + ".bvh")), None)
    if action is None:
        continue
    real = span(source)
    if real <= 0:
        continue
    made = {"generated": glob.glob(os.path.join(out, "generated", "*", "*", "%04d*.bvh" % index)),
            "reconstructed": glob.glob(os.path.join(out, "reconstructed", "%04d.bvh" % index))}
    for kind, files in made.items():
        for f in files:
            ratios.setdefault((kind, action), []).append(span(f) / real)
print("| made | action | clips | root height range, made / real: median (quartiles) |")
print("|---|---|---|---|")
for (kind, action), values in sorted(ratios.items()):
    q = statistics.quantiles(values, n=4) if len(values) >= 2 else [values[0]] * 3
    print(f"| {kind} | {action} | {len(values)} | {statistics.median(values):.2f} ({q[0]:.2f}-{q[2]:.2f}) |")
PY

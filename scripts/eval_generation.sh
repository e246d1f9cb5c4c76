#!/usr/bin/env bash
# Generated motion judged like real motion: for every captioned clip of a cache split, `nec generate` writes
# a motion for the clip's first caption onto the clip's own skeleton file, as long as the clip; then
# `nec eval t2m` compares them with the real clips (R-Precision, FID, MM-Dist, Diversity, Coverage/Novelty,
# jitter), per dataset.
#   scripts/eval_generation.sh MODEL CACHE EVALUATOR OUT_DIR [SPLIT] [SAMPLES] [CLIPS]     # MODEL: a GPT or diffusion checkpoint
# SPLIT: test (default) or val; SAMPLES per caption (default 1; 2 or more also give Multimodality);
# CLIPS: at most this many clips of each dataset, evenly spaced in the manifest's order (default: all).
# NEC_THREADS: threads of each `nec generate` (default 2).
# Writes OUT_DIR/generated/<dataset>/<the source's folder>/*.bvh (+ caption sidecars; the zoo's folders
# cNNN_<plan> give `nec eval t2m` the body plan), OUT_DIR/t2m.md and OUT_DIR/t2m.json.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 4 ]; then
  echo "usage: scripts/eval_generation.sh MODEL CACHE EVALUATOR OUT_DIR [SPLIT] [SAMPLES] [CLIPS]" >&2
  exit 2
fi
model=$1 cache=$2 evaluator=$3 out=$4 split=${5:-test} samples=${6:-1} clips=${7:-0}
nec=${NEC:-build/apps/nec}
threads=${NEC_THREADS:-2}
mkdir -p "$out/generated"
started=$SECONDS
# One line per clip: dataset, source file, seconds, first caption (tab-separated).
python3 - "$cache/manifest.json" "$split" "$clips" > "$out/clips.tsv" <<'PY'
import collections, json, sys
manifest = json.load(open(sys.argv[1]))
limit = int(sys.argv[3])
by_dataset = collections.defaultdict(list)
for clip in manifest["clips"]:
    if clip["split"] == sys.argv[2] and clip["captions"]:
        by_dataset[clip["dataset"]].append(clip)
for dataset, clips in by_dataset.items():
    if 0 < limit < len(clips):
        clips = [clips[i * len(clips) // limit] for i in range(limit)]
    for clip in clips:
        print("\t".join([dataset, clip["source"], "%.3f" % (clip["frames"] / clip["fps"]), clip["captions"][0]]))
PY
count=0
while IFS=$'\t' read -r dataset source seconds caption; do
  count=$((count + 1))
  folder="$out/generated/$dataset/$(basename "$(dirname "$source")")"
  mkdir -p "$folder"
  "$nec" generate "$caption" --skeleton "$source" --model "$model" --seconds "$seconds" --samples "$samples" \
    --seed "$count" -o "$folder/$(printf %04d "$count").bvh" --force --threads "$threads" > /dev/null
done < "$out/clips.tsv"
echo "generated $count clips of the $split split in $((SECONDS - started)) s"
"$nec" eval t2m --generated "$out/generated" --reference "$cache" --evaluator "$evaluator" --split "$split" \
  --json "$out/t2m.json" | tee "$out/t2m.md"

#!/usr/bin/env bash
# Generated motion judged like real motion: for every captioned clip of a cache split, `nec generate` writes
# a motion for the clip's first caption onto the clip's own skeleton file, as long as the clip; then
# `nec eval t2m` compares them with the real clips (R-Precision, FID, MM-Dist, Diversity, Coverage/Novelty,
# jitter), per dataset.
#   scripts/eval_generation.sh MODEL CACHE EVALUATOR OUT_DIR [SPLIT] [SAMPLES] [CLIPS]     # MODEL: a GPT or diffusion checkpoint
# SPLIT: test (default) or val; SAMPLES per caption (default 1; 2 or more also give Multimodality);
# CLIPS: at most this many clips of each dataset, evenly spaced in the manifest's order (default: all).
# NEC_THREADS: threads of each `nec generate` (default 2).
# NEC_GENERATE_OPTIONS: more options for every `nec generate`, e.g. "--solver dpm++ --steps 10".
# NEC_TARGET: the skeleton each motion is generated onto, never one that hands the model the clip's own pose:
#   rest (default): a one-frame copy of the clip's file in its rest pose (scripts/rest_pose_bvh.py), as a user
#     exports a rig (a T-pose for the zoo and CMU), which takes its creature's stance (models/default/stance);
#   apose: the same with the upper arms lowered 45 degrees (an A-pose; rigs without upper arms as in rest);
#   file: the clip's own file, its stance read from its first frame;
#   mean: the clip's own file turned around the mean pose of its motion (--rest-from-motion): the protocol before
#     the stance network, which hands the model the clip's pose (a waving clip's raised arm);
#   bind: the rest-pose copy turned around that pose itself (--rest-from-motion): what a user's T-posed rig got
#     before the stance network.
# NEC_CAPTIONS=TSV (lines: a clip's file name, a tab, a caption; `#` comments): generate from those captions
# instead, for the listed clips only; each sidecar keeps the clip's own first caption, so the evaluator scores
# a paraphrase's motion against the caption it rewrites (benchmarks/data/paraphrases.tsv).
# Writes OUT_DIR/generated/<dataset>/<the source's folder>/*.bvh (+ caption sidecars; the zoo's folders
# cNNN_<plan> give `nec eval t2m` the body plan), OUT_DIR/t2m.md and OUT_DIR/t2m.json, and OUT_DIR/rest/ (the
# one-frame rigs).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 4 ]; then
  echo "usage: scripts/eval_generation.sh MODEL CACHE EVALUATOR OUT_DIR [SPLIT] [SAMPLES] [CLIPS]" >&2
  exit 2
fi
model=$1 cache=$2 evaluator=$3 out=$4 split=${5:-test} samples=${6:-1} clips=${7:-0}
nec=${NEC:-build/apps/nec}
threads=${NEC_THREADS:-2}
target=${NEC_TARGET:-rest}
case $target in rest | apose | file | mean | bind) ;; *) echo "NEC_TARGET must be rest, apose, file, mean or bind" >&2; exit 2 ;; esac
mkdir -p "$out/generated"
started=$SECONDS
# One line per clip: dataset, source file, seconds, the caption to generate from, the clip's first caption
# (tab-separated).
python3 - "$cache/manifest.json" "$split" "$clips" "${NEC_CAPTIONS:-}" > "$out/clips.tsv" <<'PY'
import collections, json, os, sys
manifest = json.load(open(sys.argv[1]))
limit = int(sys.argv[3])
rewritten = None
if sys.argv[4]:
    rewritten = {}
    for number, line in enumerate(open(sys.argv[4]), 1):
        if line.strip() and not line.startswith("#"):
            fields = line.rstrip("\n").split("\t")
            if len(fields) != 2 or not fields[1].strip():
                sys.exit(f"{sys.argv[4]}:{number}: expected a file name, a tab and a caption")
            rewritten[fields[0]] = fields[1]
by_dataset = collections.defaultdict(list)
for clip in manifest["clips"]:
    if clip["split"] == sys.argv[2] and clip["captions"]:
        if rewritten is None or os.path.basename(clip["source"]) in rewritten:
            by_dataset[clip["dataset"]].append(clip)
if rewritten is not None and not by_dataset:
    sys.exit(f"{sys.argv[4]}: none of its clips is a captioned {sys.argv[2]} clip of {sys.argv[1]}")
for dataset, clips in by_dataset.items():
    if 0 < limit < len(clips):
        clips = [clips[i * len(clips) // limit] for i in range(limit)]
    for clip in clips:
        own = clip["captions"][0]
        prompt = rewritten[os.path.basename(clip["source"])] if rewritten is not None else own
        print("\t".join([dataset, clip["source"], "%.3f" % (clip["frames"] / clip["fps"]), prompt, own]))
PY
count=0
while IFS=$'\t' read -r dataset source seconds caption own; do
  count=$((count + 1))
  folder="$out/generated/$dataset/$(basename "$(dirname "$source")")"
  mkdir -p "$folder"
  name=$(printf %04d "$count")
  skeleton=$source rest_option=()
  case $target in
    rest | apose | bind)
      mkdir -p "$out/rest"  # beside generated/, which `nec eval t2m` reads
      skeleton="$out/rest/$name.bvh"
      arms=()
      [ "$target" = apose ] && arms=(--lower-arms 45)
      [ "$target" = bind ] && rest_option=(--rest-from-motion)
      python3 scripts/rest_pose_bvh.py "$source" "$skeleton" "${arms[@]}" ;;
    mean) rest_option=(--rest-from-motion) ;;
  esac
  "$nec" generate "$caption" --skeleton "$skeleton" --model "$model" --seconds "$seconds" --samples "$samples" \
    --seed "$count" -o "$folder/$name.bvh" --force --threads "$threads" "${rest_option[@]}" ${NEC_GENERATE_OPTIONS:-} > /dev/null
  if [ "$caption" != "$own" ]; then
    for sidecar in "$folder/$name".txt "$folder/$name"_*.txt; do
      [ -f "$sidecar" ] && printf '%s\n' "$own" > "$sidecar"
    done
  fi
done < "$out/clips.tsv"
echo "generated $count clips of the $split split in $((SECONDS - started)) s"
"$nec" eval t2m --generated "$out/generated" --reference "$cache" --evaluator "$evaluator" --split "$split" \
  --json "$out/t2m.json" | tee "$out/t2m.md"

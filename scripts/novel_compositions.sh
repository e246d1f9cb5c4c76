#!/usr/bin/env bash
# Novel compositions (How to Move Your Dragon 6.3): captions of actions a body plan never did in the zoo
# (a dragon or a centipede leaps, a person settles onto the ground, a spider sits down) generated on
# creatures of that plan, beside the same actions on plans that did them in training. Coverage and
# Novelty AUC against a reference zoo's clips of every plan whose caption is the same once the creature
# word is masked ("a dragon leaps" against every creature's "a ... leaps"), and a strip of each.
#   scripts/novel_compositions.sh GPT_CKPT EVALUATOR SKELETON_ZOO OUT_DIR [SAMPLES]
# SKELETON_ZOO: a `nec zoo` folder whose creatures carry the motions (their first clip's file gives the
# skeleton). SAMPLES per creature (default 4). Writes OUT_DIR/<name>/..., OUT_DIR/<name>.png and
# OUT_DIR/novel.md.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 4 ]; then
  echo "usage: scripts/novel_compositions.sh GPT_CKPT EVALUATOR SKELETON_ZOO OUT_DIR [SAMPLES]" >&2
  exit 2
fi
model=$1 evaluator=$2 skeletons=$3 out=$4 samples=${5:-4}
nec=${NEC:-build/apps/nec}
started=$SECONDS
mkdir -p "$out"

# The reference: a zoo of every plan, all of it a test split, large enough that each short caption
# ("a ... leaps") has a few dozen clips.
if [ ! -f "$out/reference/cache/manifest.json" ]; then
  "$nec" zoo --out "$out/reference/zoo" --creatures 180 --clips-per-creature 8 --seed 123 --quiet --force
  "$nec" prepare zoo="$out/reference/zoo/seen" --hold-out-dataset zoo -o "$out/reference/cache" --quiet > /dev/null
fi

# name, plan, caption verb phrase, whether the default models saw the plan do it (zoo/motion_synthesis.h).
compositions="dragon_leaps dragon leaps novel
centipede_leaps centipede leaps novel
biped_settles biped settles_onto_the_ground novel
spider_sits spider sits_down novel
quadruped_leaps quadruped leaps seen
biped_leaps biped leaps seen
quadruped_settles quadruped settles_onto_the_ground seen
bird_sits bird sits_down seen"

echo "| composition | caption (first creature) | default models saw it | generated | reference clips per generated | Coverage AUC | Novelty AUC | jitter (reference) |" > "$out/novel.md"
echo "|---|---|---|---|---|---|---|---|" >> "$out/novel.md"
while read -r name plan verb seen; do
  rm -rf "${out:?}/$name"
  first_caption=""
  strip_files=()
  # One skeleton file and species noun per creature of the plan.
  while IFS=$'\t' read -r file species; do
    caption="a $species ${verb//_/ }"
    [ -z "$first_caption" ] && first_caption=$caption
    folder="$out/$name/zoo/$(basename "$(dirname "$file")")"
    mkdir -p "$folder"
    "$nec" generate "$caption" --skeleton "$skeletons/$file" --model "$model" --seconds 4 --samples "$samples" \
      --seed 1 -o "$folder/generated.bvh" --force --threads 2 > /dev/null
    strip_files+=("$folder/generated_1.bvh")
  done < <(python3 - "$skeletons/manifest.json" "$plan" <<'PY'
import json, sys
seen = set()
for clip in json.load(open(sys.argv[1]))["clips"]:
    creature = clip["creature"]
    if creature["plan"] == sys.argv[2] and creature["index"] not in seen:
        seen.add(creature["index"])
        print(clip["file"] + "\t" + creature["species"])
PY
  )
  "$nec" view "${strip_files[@]:0:3}" --frames 8 -o "$out/$name.png" > /dev/null
  "$nec" eval t2m --generated "$out/$name" --reference "$out/reference/cache" --evaluator "$evaluator" \
    --across-creatures --json "$out/$name.json" > "$out/$name.md"
  python3 - "$out/$name.json" "$name" "$first_caption" "$seen" >> "$out/novel.md" <<'PY'
import json, sys
row = next(r for r in json.load(open(sys.argv[1]))["rows"] if r["name"] == "zoo")
f = lambda v, d=3: "—" if v is None else f"{v:.{d}f}"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {row['generated']} | {row['coverage_pairs'] / row['generated']:.1f} "
      f"| {f(row['coverage_auc'])} | {f(row['novelty_auc'])} | {f(row['jitter'], 0)} ({f(row['reference_jitter'], 0)}) |")
PY
done <<< "$compositions"
cat "$out/novel.md"
echo "novel compositions in $((SECONDS - started)) s: $out/novel.md, strips $out/*.png"

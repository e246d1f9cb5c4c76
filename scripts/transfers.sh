#!/usr/bin/env bash
# Five cross-species transfers with a trained tokenizer, and a viewer page that
# shows each source next to its result:
#   scripts/transfers.sh MODEL ZOO_DIR OUT_DIR
# MODEL: a checkpoint from `nec train tat`; ZOO_DIR: a folder written by
# `nec zoo` (seen/ and held_out/ creatures). Human and dog sources come from
# ../shared/data when present, else from the zoo's biped and quadruped.
# Writes OUT_DIR/*.bvh, OUT_DIR/transfers.html and the transfer checks
# (`nec eval transfer`) in OUT_DIR/transfers.md and transfers.json.
# NEC_TRANSFER_FLAGS="--free-height" (or other transfer options) is added to every transfer, to compare.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 3 ]; then
  echo "usage: scripts/transfers.sh MODEL ZOO_DIR OUT_DIR" >&2
  exit 2
fi
model=$1 zoo=$2 out=$3
nec=build/apps/nec
shared=../shared/data
mkdir -p "$out"

# The first zoo clip of a body plan (and action, when given): zoo_clip PLAN [ACTION]
zoo_clip() {
  local found
  found=$(find "$zoo" -name "*_$1_k*${2:-}*.bvh" | sort | head -n 1)
  if [ -z "$found" ]; then found=$(find "$zoo" -name "*_$1_k*.bvh" | sort | head -n 1); fi
  if [ -z "$found" ]; then echo "transfers: no $1 in $zoo" >&2; exit 1; fi
  echo "$found"
}

human_walk=$(zoo_clip biped walk)
human_wave=$(zoo_clip biped attack)
dog=$(zoo_clip quadruped trot)
dog_skeleton=$dog
if [ -d "$shared/bandai" ] && [ -d "$shared/mann_dog" ]; then
  human_walk=$(find "$shared/bandai" -name 'dataset-1_walk_normal_001.bvh' | head -n 1)
  human_wave=$(find "$shared/bandai" -name 'dataset-2_wave-both-hands_active_001.bvh' | head -n 1)
  dog="$shared/mann_dog/D1_001_KAN01_001.bvh"
  dog_skeleton=$dog
fi

# name  source  target-skeleton
pairs=(
  "human_walk_to_dog|$human_walk|$dog_skeleton"
  "dog_to_spider|$dog|$(zoo_clip spider)"
  "human_wave_to_dragon|$human_wave|$(zoo_clip dragon)"
  "dragon_walk_to_hexapod|$(zoo_clip dragon walk)|$(zoo_clip hexapod)"
  "human_walk_to_centipede|$human_walk|$(zoo_clip centipede)"
)
files=() captions=()
for pair in "${pairs[@]}"; do
  IFS='|' read -r name source target <<< "$pair"
  # shellcheck disable=SC2086  # NEC_TRANSFER_FLAGS is split into options on purpose
  "$nec" transfer "$source" --to "$target" --model "$model" -o "$out/$name.bvh" ${NEC_TRANSFER_FLAGS:-}
  files+=("$source" "$out/$name.bvh")
  captions+=(--caption "source: $(basename "$source")" --caption "$name (skeleton of $(basename "$target"))")
done
"$nec" view "${files[@]}" "${captions[@]}" --max-fps 30 --title "nec transfers" -o "$out/transfers.html"
# Speed, heading, direction, foot plants and bone lengths of each result against its source. All these files
# are +Y up: said, so that a pose too garbled to tell (a weak model's) is not measured as Z-up.
"$nec" eval transfer "${files[@]}" --up y --json "$out/transfers.json" --markdown "$out/transfers.md"
echo "open $out/transfers.html; measurements in $out/transfers.md"

#!/usr/bin/env bash
# A rig-augmented copy of a folder of BVH files (How to Move Your Dragon's "Test Set+"): every BVH below
# SRC_DIR written to the same place below OUT_DIR by `nec augment --kind KIND` (seed: the file's number in
# sorted order), with its caption sidecar (.txt) copied beside it, so `nec prepare` reads it like the source.
#   scripts/rig_augmented_copy.sh SRC_DIR OUT_DIR [KIND]     # KIND: joints (default), length, rest, axes, ...
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: scripts/rig_augmented_copy.sh SRC_DIR OUT_DIR [KIND]" >&2
  exit 2
fi
src=$1 out=$2 kind=${3:-joints}
nec=${NEC:-build/apps/nec}
if [ -e "$out" ]; then
  echo "scripts/rig_augmented_copy.sh: $out exists; remove it first" >&2
  exit 1
fi
seed=0
while IFS= read -r file; do
  relative=${file#"$src"/}
  mkdir -p "$out/$(dirname "$relative")"
  "$nec" augment "$file" --kind "$kind" --seed "$seed" -o "$out/$relative" > /dev/null
  [ -f "${file%.bvh}.txt" ] && cp "${file%.bvh}.txt" "$out/${relative%.bvh}.txt"
  seed=$((seed + 1))
done < <(find "$src" -name '*.bvh' | sort)
echo "wrote $seed rig-augmented ($kind) files to $out"

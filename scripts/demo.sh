#!/usr/bin/env bash
# Sets up, builds and runs the demo: reads real motion capture (Debian's CMU
# files, and ../shared/data when present), prints skeleton summaries, prepares
# a dataset cache and writes normalized and rig-augmented BVH to out/demo/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
nec=build/apps/nec
out=out/demo
rm -rf "$out"
mkdir -p "$out/bvh"

cmu=/usr/share/assimp/models/BVH
shared=../shared/data
inputs=("$cmu")
samples=("$cmu/01_01.bvh")
if [ -d "$shared" ]; then
  inputs+=("$shared/bandai" "$shared/mann_dog")
  samples+=("$shared/bandai/set2/data/dataset-2_wave-left-hand_normal_001.bvh" "$shared/mann_dog/D1_001_KAN01_001.bvh")
fi

echo "== skeletons"
for f in "${samples[@]}"; do
  "$nec" info --no-tree "$f"
  echo
done

echo "== normalized and augmented BVH -> $out/bvh"
for f in "${samples[@]}"; do
  name=$(basename "$f" .bvh)
  "$nec" normalize "$f" -o "$out/bvh/${name}_normalized.bvh" | tail -n 1
  for kind in rest length joints; do
    "$nec" augment "$out/bvh/${name}_normalized.bvh" --kind "$kind" --seed 1 -o "$out/bvh/${name}_${kind}.bvh"
  done
done

echo "== dataset cache -> $out/cache"
"$nec" prepare "${inputs[@]}" -o "$out/cache"

#!/usr/bin/env bash
# Leave-one-rig-out: train the skeleton encoder and the tokenizer (the README's CPU recipes) on a cache that
# holds whole real rigs out, then reconstruct those rigs' clips, as authored and re-expressed in the Maya
# convention (every bone along its parent's +X), next to the test clips of the rigs it trained on:
#   scripts/leave_one_rig_out.sh ZOO_DIR OUT_DIR DATASETS [THREADS]
# ZOO_DIR: a folder written by `nec zoo` (seen/ and held_out/); DATASETS: the real datasets to hold out,
# comma-separated, of dog (MANN), bandai and cmu (Debian's CMU files). Needs ../shared/data.
# Writes OUT_DIR/{cache,owo,tat}, OUT_DIR/recon.md (every dataset's test clips) and OUT_DIR/recon_axes.md
# (the held-out rigs' first 12 files, converted).
# NEC=path/to/nec runs another build of the binary.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 3 ]; then
  echo "usage: scripts/leave_one_rig_out.sh ZOO_DIR OUT_DIR DATASETS [THREADS]" >&2
  exit 2
fi
zoo=$1 out=$2 held=$3 threads=${4:-1}
nec=${NEC:-build/apps/nec}  # NEC=path: another build of the binary
declare -A source_dir=([bandai]=../shared/data/bandai [dog]=../shared/data/mann_dog [cmu]=/usr/share/assimp/models/BVH)
declare -A noun=([bandai]=person [dog]=dog [cmu]=person)
IFS=',' read -r -a held_datasets <<< "$held"
for name in "${held_datasets[@]}"; do
  if [ -z "${source_dir[$name]:-}" ]; then echo "leave_one_rig_out: unknown dataset '$name' (dog, bandai, cmu)" >&2; exit 2; fi
  if [ ! -d "${source_dir[$name]}" ]; then echo "leave_one_rig_out: ${source_dir[$name]} not found" >&2; exit 1; fi
done
mkdir -p "$out"

"$nec" prepare zoo="$zoo/seen" zoo_held_out="$zoo/held_out" bandai="${source_dir[bandai]}" dog="${source_dir[dog]}" \
  cmu="${source_dir[cmu]}" --hold-out-dataset "zoo_held_out,$held" --creature dog=dog,cmu=person -o "$out/cache" --quiet
"$nec" train owo --config configs/owo_cpu.json --data "$out/cache" --out "$out/owo" --threads "$threads"
"$nec" train tat --config configs/tat_cpu.json --data "$out/cache" --owo "$out/owo" --out "$out/tat" --kind nec-rvq \
  --threads "$threads"
"$nec" eval recon --data "$out/cache" --models "$out/tat" --max-clips 30 --threads "$threads" --markdown "$out/recon.md"

# The held-out rigs in another joint-orient convention: the same motion, other local rotations and offsets.
converted=() held_converted=() nouns=()
for name in "${held_datasets[@]}"; do
  mkdir -p "$out/axes/$name"
  find "${source_dir[$name]}" -name '*.bvh' | sort | head -n 12 | while read -r file; do
    "$nec" augment "$file" --kind axes -o "$out/axes/$name/$(basename "$file")" > /dev/null
  done
  converted+=("${name}_axes=$out/axes/$name")
  held_converted+=("${name}_axes")
  nouns+=("${name}_axes=${noun[$name]}")
done
"$nec" prepare "${converted[@]}" --hold-out-dataset "$(IFS=','; echo "${held_converted[*]}")" \
  --creature "$(IFS=','; echo "${nouns[*]}")" -o "$out/cache_axes" --quiet
"$nec" eval recon --data "$out/cache_axes" --models "$out/tat" --max-clips 30 --threads "$threads" \
  --markdown "$out/recon_axes.md"
echo "reconstruction: $out/recon.md (held out: $held), converted: $out/recon_axes.md"

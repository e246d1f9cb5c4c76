#!/usr/bin/env bash
# One generation per action the grown zoo added (gestures, get up, eat, shake, backwards, sideways, manners) by a
# set of models' GPT, on new zoo creatures: a person and a dog (plans the models saw) and an insect (the hexapod,
# a plan the default models never saw), as one nec view page and one PNG strip per body to look at.
#   scripts/new_actions_page.sh MODELS OUT      # e.g. models/default out/new-actions
# Writes OUT/<plan>_<n>.bvh (+ caption sidecars), OUT/new_actions.html and OUT/<plan>.png (the person from the
# front, the others from the side).
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -eq 2 ] || { echo "usage: scripts/new_actions_page.sh MODELS OUT" >&2; exit 2; }
models=$1 out=$2
nec=${NEC:-build/apps/nec}
mkdir -p "$out"
"$nec" zoo --out "$out/zoo" --plans biped,quadruped,hexapod --creatures 6 --clips-per-creature 1 --seed 123 \
  --actions idle --quiet --force
skeleton() { find "$out/zoo" -name "*_$1_*.bvh" | sort | head -n 1; }

declare -A captions=(
  [biped]="a person waves with the right hand|a person raises both hands|a person points forward|a person claps|a person bows|a person crouches down|a person kicks|a person does jumping jacks|a person stretches|a person dances|a person gets up from the ground|a person walks backwards|a person sidesteps to the left|a tired person walks slowly"
  [quadruped]="a dog eats from the ground|a dog shakes itself|a dog gets up|a dog walks backwards|a dog walks proudly"
  [hexapod]="an insect gets up|an insect walks backwards|an insect sidesteps to the right|an insect walks cautiously"
)
pages=()
for plan in biped quadruped hexapod; do
  rig=$(skeleton "$plan")
  [ -n "$rig" ] || { echo "no $plan in $out/zoo" >&2; exit 1; }
  IFS='|' read -r -a list <<< "${captions[$plan]}"
  files=()
  for i in "${!list[@]}"; do
    file="$out/${plan}_$((i + 1)).bvh"
    "$nec" generate "${list[$i]}" --skeleton "$rig" --model "$models/gpt" -o "$file" --seconds 4 --seed 1 --force \
      > /dev/null
    files+=("$file")
  done
  view=()  # a person's gestures from the front (the zoo's creatures start facing +Z)
  [ "$plan" = biped ] && view=(--facing 90)
  "$nec" view "${files[@]}" --frames 6 "${view[@]}" -o "$out/$plan.png" > /dev/null
  pages+=("${files[@]}")
done
"$nec" view "${pages[@]}" -o "$out/new_actions.html" --title "one generation per new action" > /dev/null
echo "wrote $out/new_actions.html and $out/{biped,quadruped,hexapod}.png (${#pages[@]} motions)"

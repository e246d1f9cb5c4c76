#!/usr/bin/env bash
# One caption generated onto one rig given four ways (docs/stance.md): its rest pose as one frame (a T-pose for
# CMU and Mixamo-style rigs), the same with the arms lowered 45 degrees (an A-pose), its first frame alone, and
# the file with its motion; each with its stance read from the skeleton (the default) and, for comparison, turned
# around the mean pose of the file (--rest-from-motion: the behaviour before). Prints `nec info`'s limbs line of
# every result (upper arms from hanging, thigh swing) and how far apart the T-pose's and the A-pose's results
# put the joints (scripts/compare_bvh_positions.py).
#   scripts/stance_check.sh RIG.bvh OUT_DIR ["CAPTION"] [SEED]      # default: "a person walks forward", seed 1
# RIG.bvh may be a one-frame rig; then "first frame" and "with motion" are that frame. NEC_MODEL: the model
# (default: the default GPT); NEC_STANCE: a stance network instead of models/default/stance.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 2 ]; then
  echo "usage: scripts/stance_check.sh RIG.bvh OUT_DIR [\"CAPTION\"] [SEED]" >&2
  exit 2
fi
rig=$1 out=$2 caption=${3:-a person walks forward} seed=${4:-1}
nec=${NEC:-build/apps/nec}
model=(); [ -n "${NEC_MODEL:-}" ] && model=(--model "$NEC_MODEL")
stance=(); [ -n "${NEC_STANCE:-}" ] && stance=(--stance "$NEC_STANCE")
mkdir -p "$out/rigs"
python3 scripts/rest_pose_bvh.py "$rig" "$out/rigs/tpose.bvh"
python3 scripts/rest_pose_bvh.py "$rig" "$out/rigs/apose.bvh" --lower-arms 45
python3 scripts/rest_pose_bvh.py "$rig" "$out/rigs/first.bvh" --first-frame
cp "$rig" "$out/rigs/motion.bvh"
generate() {  # generate NAME RIG [OPTIONS...]
  local name=$1 skeleton=$2
  shift 2
  "$nec" generate "$caption" --skeleton "$skeleton" --seconds 4 --seed "$seed" -o "$out/$name.bvh" --force \
    "${model[@]}" "$@" > /dev/null
  printf '%-28s %s\n' "$name" "$("$nec" info "$out/$name.bvh" --no-tree | grep '^limbs' || echo 'limbs: not a person')"
}
echo "\"$caption\", seed $seed, onto $rig:"
for rig_kind in tpose apose first motion; do
  generate "$rig_kind" "$out/rigs/$rig_kind.bvh" "${stance[@]}"
done
for rig_kind in tpose motion; do
  generate "${rig_kind}_mean_pose" "$out/rigs/$rig_kind.bvh" --rest-from-motion
done
printf '%-28s %s\n' "T-pose against A-pose" "$(python3 scripts/compare_bvh_positions.py "$out/tpose.bvh" "$out/apose.bvh")"

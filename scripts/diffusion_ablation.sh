#!/usr/bin/env bash
# The diffusion model's ablation (How to Move Your Dragon, Table 1 and Figure 4) at the CPU configs' size:
# each variant trained in two stages on CACHE (configs/diffusion_{pose,motion}_cpu.json with one change),
# then judged by scripts/eval_generation.sh on EVAL_CACHE's test split with EVALUATOR.
#   scripts/diffusion_ablation.sh CACHE OWO EVAL_CACHE EVALUATOR OUT_DIR [CLIPS] [VARIANT ...]
# Variants: owo (the default: OwO joint identity, rig augmentation), tree (TreePE + RestPE instead of OwO),
# no-augment (rig augmentation off); all three by default. CLIPS: at most this many test clips per dataset
# (default 60). Writes OUT_DIR/<variant>/{pose,motion} and OUT_DIR/<variant>/eval/t2m.md; about 40 minutes
# per variant on 2 cores (training 28, generation and evaluation 11). NEC_THREADS (default 2): threads of
# every training and generation (1 lets two jobs share a 2-core machine without their threads spinning).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 5 ]; then
  echo "usage: scripts/diffusion_ablation.sh CACHE OWO EVAL_CACHE EVALUATOR OUT_DIR [CLIPS] [VARIANT ...]" >&2
  exit 2
fi
cache=$1 owo=$2 eval_cache=$3 evaluator=$4 out=$5 clips=${6:-60}
shift $(( $# < 6 ? $# : 6 ))
variants=("$@")
[ ${#variants[@]} -gt 0 ] || variants=(owo tree no-augment)
nec=${NEC:-build/apps/nec}
threads=${NEC_THREADS:-2}
for variant in "${variants[@]}"; do
  dir="$out/$variant"
  mkdir -p "$dir"
  # The variant's configs: the CPU configs with its one change.
  python3 - "$variant" "$dir" <<'PY'
import json, sys
variant, dir = sys.argv[1], sys.argv[2]
pose = json.load(open("configs/diffusion_pose_cpu.json"))
motion = json.load(open("configs/diffusion_motion_cpu.json"))
if variant == "tree":
    pose["model"]["joint_identity"] = "tree"
elif variant == "no-augment":
    pose["data"]["augment"]["probability"] = 0.0
    motion["data"]["augment"]["probability"] = 0.0
elif variant != "owo":
    sys.exit(f"unknown variant {variant} (owo, tree, no-augment)")
pose["comment"] = motion["comment"] = f"scripts/diffusion_ablation.sh variant {variant}"
json.dump(pose, open(f"{dir}/pose.json", "w"), indent=1)
json.dump(motion, open(f"{dir}/motion.json", "w"), indent=1)
PY
  echo "== $variant: training"
  "$nec" train diffusion --stage pose --config "$dir/pose.json" --data "$cache" --owo "$owo" --out "$dir/pose" \
    --threads "$threads" --force > "$dir/pose.log"
  "$nec" train diffusion --stage motion --config "$dir/motion.json" --data "$cache" --pose "$dir/pose" \
    --out "$dir/motion" --threads "$threads" --force > "$dir/motion.log"
  tail -n 2 "$dir/pose.log" "$dir/motion.log"
  echo "== $variant: generation and evaluation"
  scripts/eval_generation.sh "$dir/motion" "$eval_cache" "$evaluator" "$dir/eval" test 1 "$clips"
done

#!/usr/bin/env bash
# Trains the default models (models/default/) that `nec generate`, `nec transfer`, `nec retrieve` and
# `nec demo` use when no model is given, on data the project may ship models of: the zoo (every body
# plan but the hexapod, kept out so the demo and the report can show a plan the models never saw),
# Debian's CMU files and the free CMU takes of ../shared/data/cmu (with their take descriptions). Never
# ../shared/data/bandai or mann_dog: their licenses are non-commercial.
#   scripts/train_default_models.sh [WORK_DIR] [OUT_DIR]     # defaults: out/default-models, models/default
# On 2 cores (2026-12-06, 3,661 clips): the data step 30 s, OwO 1.5 min, the tokenizer and the evaluator side by
# side (the tokenizer's 2,000 steps at ~0.93 steps/s: ~36 min; alone on two threads 22 min) and 57 min, the GPT
# (2,400 steps) 7 min; the diffusion model's two stages 15 and 28 min (2026-12-06, beside lighter work). Writes
# OUT_DIR/{gpt,evaluator,diffusion,stance} (the GPT holds its tokenizer in gpt/tat, which holds its OwO encoder;
# the diffusion model holds a copy of that encoder) without their training state; OUT_DIR/README.md
# (kept) says how its numbers were measured. Run again after a stop, it goes on where it stopped (finished
# stages are skipped, an interrupted training resumes); remove WORK_DIR to start over.
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-out/default-models} out=${2:-models/default}
nec=${NEC:-build/apps/nec}  # NEC=...: another nec binary (e.g. a copy, while build/ is rebuilt)
steps=()                     # STEPS=N: every training ends at step N (a quick trial of the whole pipeline)
[ -n "${STEPS:-}" ] && steps=(--steps "$STEPS")
started=$SECONDS
step() { echo; echo "== [$(( (SECONDS - started) / 60 )) min] $*"; }
mkdir -p "$work"

# Each stage runs once: a finished one (WORK/<stage>.done) is skipped and an interrupted training resumes from
# its last checkpoint, so that running the script again after a stop goes on where it stopped.
train() {  # train STAGE ARGS...: `nec train ARGS` into WORK/STAGE
  local stage=$1 mode=--force
  shift
  if [ -f "$work/$stage.done" ]; then echo "$stage: trained before ($work/$stage.done)"; return 0; fi
  [ -f "$work/$stage/training.json" ] && mode=--resume
  "$nec" train "$@" --out "$work/$stage" "$mode" "${steps[@]}"
  touch "$work/$stage.done"
}

shared_cmu=${NEC_SHARED_CMU:-../shared/data/cmu}
debian_cmu=/usr/share/assimp/models/BVH
step "data: zoo (hexapods held out), Debian's CMU files and the shared CMU takes"
[ -f "$shared_cmu/descriptions.csv" ] || { echo "no $shared_cmu/descriptions.csv (set NEC_SHARED_CMU)" >&2; exit 1; }
if [ ! -f "$work/data.done" ]; then
  "$nec" zoo --out "$work/zoo" --creatures 225 --clips-per-creature 12 --seed 11 --hold-out hexapod --quiet --force
  # More of the creatures users ask for most (people, four-legged animals, birds): a plan's clips are spread
  # over all its actions, and a person has nineteen.
  "$nec" zoo --out "$work/zoo_more" --plans biped,quadruped,bird --creatures 48 --clips-per-creature 12 --seed 12 \
    --quiet --force
  # Debian's takes that the shared set holds too (01_01, another conversion) are left out: one take, one split.
  rm -rf "$work/cmu_debian" && mkdir -p "$work/cmu_debian"
  for take in "$debian_cmu"/*.bvh; do
    [ -e "$shared_cmu/bvh/$(basename "$take")" ] || ln -s "$take" "$work/cmu_debian/"
  done
  "$nec" prepare zoo="$work/zoo/seen" zoo_more="$work/zoo_more/seen" zoo_held_out="$work/zoo/held_out" \
    cmu="$work/cmu_debian" cmu_free="$shared_cmu/bvh" --descriptions "$shared_cmu/descriptions.csv" \
    --hold-out-dataset zoo_held_out --creature cmu=person,cmu_free=person -o "$work/cache" --quiet
  touch "$work/data.done"
fi

# The stance network (a rig given without motion -> its creature's stance): every rig of the cache but the held-out
# hexapods and two CMU subjects, kept out so that its error on people it never saw is measured.
step "stance network"
if [ ! -f "$work/stance.done" ]; then
  "$nec" train stance --data "$work/cache" --out "$work/stance" --hold-out '*/bvh/13_*,*/bvh/14_*' --names --steps 1200 --batch 16 --threads 1
  touch "$work/stance.done"
fi

step "skeleton encoder"
train owo owo --config configs/owo_default.json --data "$work/cache" --threads 2

step "tokenizer and evaluator, side by side (1 thread each)"
train tat tat --config configs/tat_cpu.json --data "$work/cache" --owo "$work/owo" --threads 1 > "$work/tat.log" 2>&1 &
tat=$!
train evaluator evaluator --config configs/evaluator_cpu.json --data "$work/cache" --owo "$work/owo" --threads 1 \
  > "$work/evaluator.log" 2>&1 &
evaluator=$!
wait $tat || { tail -n 20 "$work/tat.log"; exit 1; }
wait $evaluator || { tail -n 20 "$work/evaluator.log"; exit 1; }
tail -n 3 "$work/tat.log" "$work/evaluator.log"

step "GPT"
train gpt gpt --config configs/gpt_cpu.json --data "$work/cache" --tat "$work/tat" --threads 2

step "diffusion model: the pose stage, then the motion stage on it"
train diffusion_pose diffusion --stage pose --config configs/diffusion_pose_cpu.json --data "$work/cache" \
  --owo "$work/owo" --threads 2
train diffusion diffusion --stage motion --config configs/diffusion_motion_cpu.json --data "$work/cache" \
  --pose "$work/diffusion_pose" --threads 2

step "copy into $out (models only, no training state)"
rm -rf "$out.tmp"
mkdir -p "$out.tmp"
cp -r "$work/gpt" "$out.tmp/gpt"
cp -r "$work/evaluator/best" "$out.tmp/evaluator"
cp -r "$work/diffusion" "$out.tmp/diffusion"
cp -r "$work/stance" "$out.tmp/stance"
find "$out.tmp" \( -name training.json -o -name optimizer.pt \) -delete
rm -rf "$out.tmp/evaluator/best"
[ -f "$out/README.md" ] && cp "$out/README.md" "$out.tmp/README.md"
rm -rf "$out"
mv "$out.tmp" "$out"
du -sh "$out"
step "done in $(( (SECONDS - started) / 60 )) min"

#!/usr/bin/env bash
# Measures a set of default models (scripts/train_default_models.sh's output) as models/default/README.md
# reports them:
#  - generation by the GPT on new zoo creatures, one all-test cache per action family (locomotion, gestures,
#    vertical: jump / sit / lie down, flight, other: idle / attack / eat / shake), every plan that has the
#    family's actions and the hexapods (the plan the models never saw): R@3 mixed and within plan, FID,
#    jitter (scripts/eval_generation.sh, judged by the models' own evaluator), beside the real and the
#    tokenizer-reconstructed clips' R@3 (`nec eval retrieval`);
#  - how much of the real clips' vertical range generated and tokenizer-reconstructed jumps, sits and lie-downs
#    keep (scripts/vertical_range.sh);
#  - generation on the test split of the training cache (the shared CMU takes the models never trained on
#    come out as their own group, cmu_free);
#  - the user-style queries of benchmarks/data/queries.tsv through `nec retrieve` (scripts/eval_queries.py) on
#    the locomotion and other families' caches together, with these models' evaluator and, when given, a
#    baseline's;
#  - with a baseline, its GPT on the same gestures and vertical clips (judged by these models' evaluator) and
#    the vertical range it keeps.
#   scripts/eval_default_models.sh MODELS TRAIN_CACHE OUT [BASELINE_MODELS]
# CLIPS: at most this many clips per dataset and family (default 60); SAMPLES per caption (default 2).
# Writes OUT/<family>/{zoo,cache,gpt/t2m.md,retrieval.md}, OUT/vertical_range.md, OUT/train-test/t2m.md, OUT/queries*.md and
# OUT/summary.md (every table, in that order).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 3 ]; then
  echo "usage: scripts/eval_default_models.sh MODELS TRAIN_CACHE OUT [BASELINE_MODELS]" >&2
  exit 2
fi
models=$1 train_cache=$2 out=$3 baseline=${4:-}
nec=${NEC:-build/apps/nec}
clips=${CLIPS:-60} samples=${SAMPLES:-2}
started=$SECONDS
mkdir -p "$out"
step() { echo; echo "== [$(( (SECONDS - started) / 60 )) min] $*"; }

# family: actions; plans that have them (the hexapod, held out, where it has them)
families=(
  "locomotion:walk,trot,run,gallop,turn,slither,swim:"
  "gestures:wave,raise_hands,point,clap,bow,crouch,kick,jumping_jacks,stretch,dance:biped"
  "vertical:jump,sit,lie_down:biped,quadruped,hexapod,spider,bird,dragon,crab,ungulate,elephant,ground_bird,hopper,dinosaur,primate"
  "flight:fly,glide,take_off,flap_wings:bird,dragon,ground_bird"
  "other:idle,attack,eat,shake:"
)
for entry in "${families[@]}"; do
  IFS=: read -r family actions plans <<< "$entry"
  step "$family ($actions)"
  plan_args=() hold=()
  [ -n "$plans" ] && plan_args=(--plans "$plans")
  case ",${plans:-hexapod}," in *,hexapod,*) hold=(--hold-out hexapod) ;; esac
  "$nec" zoo --out "$out/$family/zoo" --creatures 60 --clips-per-creature 4 --seed 99 --actions "$actions" \
    "${plan_args[@]}" "${hold[@]}" --quiet --force
  inputs=(zoo="$out/$family/zoo/seen") held=zoo
  if [ -d "$out/$family/zoo/held_out" ]; then
    inputs+=(zoo_held_out="$out/$family/zoo/held_out")
    held=zoo,zoo_held_out
  fi
  "$nec" prepare "${inputs[@]}" --hold-out-dataset "$held" -o "$out/$family/cache" --quiet
  scripts/eval_generation.sh "$models/gpt" "$out/$family/cache" "$models/evaluator" "$out/$family/gpt" test \
    "$samples" "$clips" > "$out/$family/gpt.log"
  tail -n 40 "$out/$family/gpt/t2m.md"
  "$nec" eval retrieval --data "$out/$family/cache" --evaluator "$models/evaluator" --tokenizer "$models/gpt/tat" \
    | tee "$out/$family/retrieval.md"
done

step "vertical range of generated and reconstructed jumps, sits and lie-downs"
scripts/vertical_range.sh "$out/vertical/gpt" "$models/gpt/tat" | tee "$out/vertical_range.md"
if [ -n "$baseline" ]; then
  # The baseline's GPT on the same gestures and vertical clips, judged by these models' evaluator.
  for family in gestures vertical; do
    step "$family: the baseline's GPT ($baseline/gpt)"
    scripts/eval_generation.sh "$baseline/gpt" "$out/$family/cache" "$models/evaluator" "$out/$family/gpt-baseline" \
      test "$samples" "$clips" > "$out/$family/gpt-baseline.log"
    tail -n 40 "$out/$family/gpt-baseline/t2m.md"
  done
  scripts/vertical_range.sh "$out/vertical/gpt-baseline" "$baseline/gpt/tat" | tee "$out/vertical_range-baseline.md"
fi

step "the training cache's test split (the shared CMU test takes: cmu_free)"
scripts/eval_generation.sh "$models/gpt" "$train_cache" "$models/evaluator" "$out/train-test" test "$samples" \
  "$clips" > "$out/train-test.log"
tail -n 40 "$out/train-test/t2m.md"

step "user-style queries"
"$nec" prepare zoo="$out/locomotion/zoo/seen" zoo_other="$out/other/zoo/seen" cmu=/usr/share/assimp/models/BVH \
  --creature cmu=person -o "$out/queries-cache" --quiet
python3 scripts/eval_queries.py "$out/queries-cache" --evaluator "$models/evaluator" | tee "$out/queries.md"
if [ -n "$baseline" ]; then
  python3 scripts/eval_queries.py "$out/queries-cache" --evaluator "$baseline/evaluator" | tee "$out/queries-baseline.md"
fi

{
  for entry in "${families[@]}"; do
    family=${entry%%:*}
    echo "## $family"; echo; cat "$out/$family/gpt/t2m.md"; echo; cat "$out/$family/retrieval.md"; echo
  done
  echo "## vertical range"; echo; cat "$out/vertical_range.md"; echo
  if [ -n "$baseline" ]; then
    for family in gestures vertical; do
      echo "## $family, the baseline's GPT"; echo; cat "$out/$family/gpt-baseline/t2m.md"; echo
    done
    echo "## vertical range, the baseline's GPT"; echo; cat "$out/vertical_range-baseline.md"; echo
  fi
  echo "## training cache, test split"; echo; cat "$out/train-test/t2m.md"; echo
  echo "## queries"; echo; head -n 2 "$out/queries.md"
  [ -n "$baseline" ] && { echo; echo "baseline:"; head -n 2 "$out/queries-baseline.md"; }
} > "$out/summary.md"
step "done in $(( (SECONDS - started) / 60 )) min: $out/summary.md"

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
#  - the user-style queries of benchmarks/data/queries.tsv and queries_heldout.tsv through `nec retrieve`
#    (scripts/eval_queries.py) on 96 new zoo creatures of every plan and Debian's CMU files, with these models'
#    evaluator (blended with the clips' captions, `nec retrieve`'s default, and by the motions alone) and, when
#    given, a baseline's; and the near-action confusion tables (scripts/confusion_table.py);
#  - with a baseline, its GPT on the same gestures and vertical clips (judged by these models' evaluator) and
#    the vertical range it keeps.
#   scripts/eval_default_models.sh MODELS TRAIN_CACHE OUT [BASELINE_MODELS]
# CLIPS: at most this many clips per dataset and family (default 60); SAMPLES per caption (default 2).
# Writes OUT/<family>/{zoo,cache,gpt/t2m.md,retrieval.md}, OUT/vertical_range.md, OUT/train-test/t2m.md, OUT/queries*.md,
# OUT/confusion.md and
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

step "user-style queries and near actions"
"$nec" zoo --out "$out/queries-zoo" --creatures 96 --clips-per-creature 8 --seed 99 --quiet --force
"$nec" prepare zoo="$out/queries-zoo/seen" cmu=/usr/share/assimp/models/BVH --creature cmu=person \
  -o "$out/queries-cache" --quiet
for set in queries queries_heldout; do
  python3 scripts/eval_queries.py "$out/queries-cache" --queries "benchmarks/data/$set.tsv" --evaluator "$models/evaluator" \
    | tee "$out/$set.md"
  python3 scripts/eval_queries.py "$out/queries-cache" --queries "benchmarks/data/$set.tsv" --evaluator "$models/evaluator" \
    --caption-weight 0 > "$out/$set-motions.md"
  if [ -n "$baseline" ]; then
    python3 scripts/eval_queries.py "$out/queries-cache" --queries "benchmarks/data/$set.tsv" --evaluator "$baseline/evaluator" \
      > "$out/$set-baseline.md"
  fi
done
"$nec" zoo --out "$out/near-zoo" --plans biped,quadruped,bird,dragon,ungulate \
  --actions walk,trot,run,gallop,sit,lie_down,fly,glide,flap_wings,take_off --creatures 80 --clips-per-creature 8 --seed 99 \
  --quiet --force
"$nec" prepare zoo="$out/near-zoo/seen" -o "$out/near-cache" --quiet
python3 scripts/confusion_table.py "$out/near-cache" --evaluator "$models/evaluator" | tee "$out/confusion.md"

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
  for set in queries queries_heldout; do
    echo "## $set (blended with the captions; by the motions alone)"; echo
    head -n 2 "$out/$set.md"; sed -n 2p "$out/$set-motions.md"
    [ -n "$baseline" ] && { echo; echo "baseline:"; head -n 2 "$out/$set-baseline.md"; }
    echo
  done
  echo "## near actions"; echo; cat "$out/confusion.md"
} > "$out/summary.md"
step "done in $(( (SECONDS - started) / 60 )) min: $out/summary.md"

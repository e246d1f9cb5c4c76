#!/usr/bin/env bash
# Sets up, builds and runs the demo (`nec demo`): a small zoo of procedural
# creatures plus Debian's CMU motion capture (and ../shared/data when present)
# become one dataset cache; normalized and augmented BVH, PNG strips and viewer
# pages are written to out/demo/ (open out/demo/index.html in a browser).
# NEC_TAT_MODEL=CKPT adds five transfers with that tokenizer (see the end).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
nec=build/apps/nec

shared=../shared/data
extra=()
if [ -d "$shared/bandai" ] && [ -d "$shared/mann_dog" ]; then
  extra=(--extra "bandai=$shared/bandai,dog=$shared/mann_dog")
fi

echo "== a real file: nec info"
"$nec" info --no-tree /usr/share/assimp/models/BVH/01_01.bvh
echo
echo "== nec demo ${extra[*]}"
"$nec" demo "${extra[@]}"

# With a trained tokenizer (NEC_TAT_MODEL=runs/tat bash scripts/demo.sh): five
# cross-species transfers, a page showing each next to its source, and the
# transfer checks (speed, heading, feet, bones) in out/demo/transfers/.
if [ -n "${NEC_TAT_MODEL:-}" ]; then
  echo
  echo "== transfers with $NEC_TAT_MODEL"
  "$nec" zoo --out out/demo/transfer_zoo --creatures 9 --clips-per-creature 4 --seed 1 --quiet --force
  scripts/transfers.sh "$NEC_TAT_MODEL" out/demo/transfer_zoo out/demo/transfers
fi

echo
echo "== next: open out/demo/index.html in a browser, or the studio, where you type captions for a rig of yours:"
echo "   $nec serve --db out/demo/cache        # then open http://127.0.0.1:8080/ (Ctrl-C stops it)"

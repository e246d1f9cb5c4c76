#!/usr/bin/env bash
# Checks that BVH files written by nec import in Blender and in three.js
# BVHLoader with the joints, end sites and frames nec's reader sees, and with
# the same joint positions as the source file (see blender_import.py and
# threejs_import.mjs for exactly what each importer is asked).
#
#   tests/interop/check_import.sh NEC_REWRITE_BVH WORKDIR [SOURCE.bvh ...]
#
# Without sources it takes the Debian CMU files and, when ../shared/data is
# there, two Bandai and the two smallest MANN dog files; one Bandai and one
# dog file (both ZXY) are also rewritten in ZYX order, and one CMU file (ZYX)
# in YXZ. Sources are only read; the
# rewritten files go to WORKDIR. Exit status: 0 all passed, 1 a check failed,
# 77 (CTest: skipped) when neither blender nor node + three is installed; with one of them, that importer is
# checked and the run passes saying what was not checked (fails instead under NEC_REQUIRE_DOWNLOADS, as in CI).
# scripts/interop.sh installs everything and runs this.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
if [ $# -lt 2 ]; then
  echo "usage: $0 NEC_BINARY WORKDIR [SOURCE.bvh ...]" >&2
  exit 2
fi
nec=$1
work=$2
shift 2
three_dir=${NEC_THREE_DIR:-$root/benchmarks/node_modules/three}

have_blender=1; have_three=1
command -v blender >/dev/null || have_blender=0
if ! command -v node >/dev/null || [ ! -f "$three_dir/examples/jsm/loaders/BVHLoader.js" ]; then have_three=0; fi
if [ $have_blender = 0 ] && [ $have_three = 0 ]; then
  echo "interop: skipped: neither blender nor node + three ($three_dir) is installed; run scripts/interop.sh"
  exit 77
fi

sources=("$@")
reordered=()
if [ ${#sources[@]} -eq 0 ]; then
  cmu=(/usr/share/assimp/models/BVH/*.bvh)
  [ -f "${cmu[0]}" ] && sources+=("${cmu[@]}") && reordered+=("${cmu[0]}:YXZ")
  shared="$root/../shared/data"
  if [ -d "$shared" ]; then
    mapfile -t bandai < <(for set in set1 set2; do find "$shared/bandai/$set" -name '*.bvh' | sort | head -n 1; done)
    mapfile -t dog < <(ls -S "$shared"/mann_dog/*.bvh 2>/dev/null | tail -n 2)
    sources+=("${bandai[@]}" "${dog[@]}")
    [ ${#bandai[@]} -gt 0 ] && reordered+=("${bandai[0]}:ZYX")
    [ ${#dog[@]} -gt 0 ] && reordered+=("${dog[-1]}:ZYX")
  fi
fi
if [ ${#sources[@]} -eq 0 ]; then
  echo "interop: no BVH files to check (install assimp-testmodels or pass files)" >&2
  exit 1
fi

mkdir -p "$work"
manifest="$work/manifest.tsv"
: > "$manifest"
counts() {  # joints, end sites, frames of a file as nec's reader sees them
  "$nec" info --json "$1" | sed -E 's/.*"joints": ([0-9]+), "end_sites": ([0-9]+), "frames": ([0-9]+).*/\1\t\2\t\3/'
}
add() {  # add SOURCE LABEL [ORDER]
  local source=$1 label=$2 written="$work/$2.bvh"
  if [ $# -eq 3 ]; then "$nec" convert "$source" -o "$written" --order "$3" >/dev/null; else "$nec" convert "$source" -o "$written" >/dev/null; fi
  local seen; seen=$(counts "$written")
  if [ "$seen" != "$(counts "$source")" ]; then
    echo "interop: FAIL $label: nec reads $(counts "$source" | tr '\t' ' ') in the source but $(echo "$seen" | tr '\t' ' ') in its own output" >&2
    exit 1
  fi
  printf '%s\t%s\t%s\t%s\n' "$label" "$source" "$written" "$seen" >> "$manifest"
}
for source in "${sources[@]}"; do add "$source" "$(basename "$source" .bvh)"; done
for entry in "${reordered[@]}"; do  # SOURCE:ORDER
  order=${entry##*:}
  add "${entry%:*}" "$(basename "${entry%:*}" .bvh)_${order,,}" "$order"
done
echo "interop: $(wc -l < "$manifest") files written by nec in $work (label, joints, end sites, frames):"
cut -f1,4- "$manifest" | sed 's/^/  /'

status=0
if [ $have_three = 1 ]; then
  node "$here/threejs_import.mjs" --three "$three_dir" "$manifest" || status=1
else
  echo "interop: three.js part skipped: node or $three_dir missing"
fi
if [ $have_blender = 1 ]; then
  if ! blender -b --factory-startup --python-exit-code 1 --python "$here/blender_import.py" -- "$manifest" \
      > "$work/blender.log" 2>&1; then
    status=1
    grep -E '^blender [0-9]' "$work/blender.log" || true
    echo "interop: blender failed; last lines of $work/blender.log:"
    tail -n 20 "$work/blender.log"
  else
    grep -E '^blender [0-9]' "$work/blender.log"
  fi
else
  echo "interop: Blender part skipped: blender not installed"
fi

if [ $status -ne 0 ]; then
  echo "interop: FAILED"
  exit 1
fi
if [ $have_blender = 0 ] || [ $have_three = 0 ]; then
  # One importer checked is a pass of that importer, not a skip; CI, which installs both (scripts/test.sh), does
  # not pass on half the check.
  missing=$([ $have_blender = 0 ] && echo Blender || echo three.js)
  if [ -n "${NEC_REQUIRE_DOWNLOADS:-}" ]; then
    echo "interop: FAILED: $missing is missing (NEC_REQUIRE_DOWNLOADS is set: CI must check both importers)"
    exit 1
  fi
  echo "interop: passed in $([ $have_blender = 1 ] && echo Blender || echo three.js); $missing not checked (not installed)"
  exit 0
fi
echo "interop: all files import in three.js and Blender as nec reads them"

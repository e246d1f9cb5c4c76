#!/usr/bin/env bash
# Checks the Blender add-on (blender/nec_blender) in Blender itself: installs it from its zip as a user would, then
# runs its Generate, Transfer and Search operators on a CMU BVH armature and on the rig of huesitos.fbx (assimp-testmodels)
# (FBX), with nec's default models (see test_addon.py for what is checked). The add-on's runner is also checked
# with plain Python (test_runner.py).
#
#   tests/blender/check_addon.sh NEC_BINARY WORKDIR
#
# Exit status: 0 passed, 1 a check failed, 77 (CTest: skipped) when blender, assimp-testmodels or the default
# models are missing (scripts/test.sh and scripts/interop.sh install Blender). Writes only inside WORKDIR.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
[ $# -eq 2 ] || { echo "usage: $0 NEC_BINARY WORKDIR" >&2; exit 2; }
nec=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
work=$2

python3 "$here/test_runner.py"
command -v blender >/dev/null || { echo "blender add-on: skipped: blender is not installed (scripts/interop.sh)"; exit 77; }
models=/usr/share/assimp/models
[ -f "$models/FBX/huesitos.fbx" ] || { echo "blender add-on: skipped: assimp-testmodels is not installed"; exit 77; }
[ -f "$root/models/default/gpt/config.json" ] || { echo "blender add-on: skipped: no default models"; exit 77; }

rm -rf "$work" && mkdir -p "$work"
work=$(cd "$work" && pwd)
# The add-on as users install it: a zip of its folder (Preferences → Add-ons → Install).
(cd "$root/blender" && python3 -m zipfile -c "$work/nec_blender.zip" nec_blender/)
# A small database to search: people of the zoo.
"$nec" zoo --out "$work/zoo" --plans biped --creatures 2 --clips-per-creature 4 --seed 5 --quiet
"$nec" prepare zoo="$work/zoo/seen" -o "$work/db" --quiet
# Blender installs add-ons into its user folders: keep them (and its temp files) inside WORKDIR.
export BLENDER_USER_CONFIG="$work/blender/config" BLENDER_USER_SCRIPTS="$work/blender/scripts" TMPDIR="$work/tmp"
mkdir -p "$TMPDIR"
blender -b --factory-startup --python-exit-code 1 --python "$here/test_addon.py" -- \
  "$nec" "$work/nec_blender.zip" "$work/db" "$models"

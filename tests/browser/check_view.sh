#!/usr/bin/env bash
# Opens pages written by `nec view` in headless Chromium and checks them.
#
#   tests/browser/check_view.sh NEC_BINARY WORKDIR [CLIP.bvh ...]
#
# Without clips it takes Debian's CMU files 01_01 (copied next to a clip.txt
# caption sidecar) and Boxing_Toes, plus 01_01 normalized by nec (diameter 1,
# a size very different from the CMU centimetres), and the rigged asset
# Testwuson.X (its Wuson_Walk): three.js's GLTFLoader must load its skinned
# mesh, whose bones must move within 1e-3 body sizes of nec's joints. For each page: Chromium
# (--dump-dom) must report state "ready" with no errors in the page's status
# block, every clip with the joints, end sites and frames of `nec info`, joint
# positions within 1e-4 body sizes of nec's forward kinematics, every joint in
# view, the frame of t = 1 s shown (the page is opened as view.html#t=1), the
# caption in the DOM and no uncaught exceptions on stderr; a screenshot
# (WORKDIR/view.png, 1280x720) must show left (blue) and right (red) bones.
# Host name resolution is switched off, so a page that fetched anything fails.
# Exit status: 0 passed, 1 failed, 77 (CTest: skipped) when chromium or
# python3 is missing or nec was built without three.js.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
if [ $# -lt 2 ]; then
  echo "usage: $0 NEC_BINARY WORKDIR [CLIP.bvh ...]" >&2
  exit 2
fi
nec=$1
work=$2
shift 2
chromium=${NEC_CHROMIUM:-chromium}
if ! command -v "$chromium" >/dev/null; then
  echo "browser: skipped: $chromium is not installed (scripts/setup_viewer_assets.sh installs it)"
  exit 77
fi
if ! command -v python3 >/dev/null; then
  echo "browser: skipped: python3 is not installed"
  exit 77
fi

rm -rf "$work"
mkdir -p "$work"
clips=("$@")
caption=""
if [ ${#clips[@]} -eq 0 ]; then
  cmu=/usr/share/assimp/models/BVH
  if [ ! -f "$cmu/01_01.bvh" ]; then
    echo "browser: no clips given and $cmu/01_01.bvh is missing (install assimp-testmodels)" >&2
    exit 1
  fi
  cp "$cmu/01_01.bvh" "$work/jump.bvh"
  caption="a person jumps forward and turns around"
  printf '%s\n' "$caption" > "$work/jump.txt"
  "$nec" normalize "$cmu/01_01.bvh" -o "$work/jump_normalized.bvh" >/dev/null
  clips=("$work/jump.bvh" "$cmu/Boxing_Toes.bvh" "$work/jump_normalized.bvh")
  # A rigged asset: its skinned mesh must load in three.js's GLTFLoader and move with nec's joints.
  wuson=/usr/share/assimp/models/X/Testwuson.X
  [ -f "$wuson" ] && clips+=("$wuson#Wuson_Walk")
fi

# What nec reads: name, joints, end sites, frames, fps per clip, and whether it is an asset (shown with its mesh).
expected="$work/expected.tsv"
: > "$expected"
for clip in "${clips[@]}"; do
  info=$("$nec" info --no-tree "$clip")
  joints=$(sed -nE 's/^joints +([0-9]+) \(([0-9]+) end sites.*/\1\t\2/p' <<< "$info")
  frames=$(sed -nE "s/^(frames +|animation '.*': )([0-9]+)( frames)? at ([0-9.e+-]+) fps.*/\2\t\4/p" <<< "$info")
  file=$(basename "${clip%%#*}")
  asset=1
  [ "${file##*.}" = bvh ] && asset=0
  printf '%s\t%s\t%s\t%s\n' "${file%.*}" "$joints" "$frames" "$asset" >> "$expected"
done

page="$work/view.html"
if ! "$nec" view "${clips[@]}" -o "$page" > "$work/nec_view.log" 2>&1; then
  if grep -q "built without three.js" "$work/nec_view.log"; then
    echo "browser: skipped: $(cat "$work/nec_view.log")"
    exit 77
  fi
  cat "$work/nec_view.log" >&2
  exit 1
fi
echo "browser: $(cat "$work/nec_view.log")"

flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --enable-unsafe-swiftshader --window-size=1280,720
       --virtual-time-budget=10000 --enable-logging=stderr --v=0 '--host-resolver-rules=MAP * ~NOTFOUND')
run_chromium() {  # run_chromium LOG ARGS...: a fresh profile each time
  local log=$1 profile
  shift
  profile=$(mktemp -d "$work/profile.XXXXXX")
  timeout 180 "$chromium" "${flags[@]}" --user-data-dir="$profile" "$@" 2> "$log"
  rm -rf "$profile"
}
time=1
run_chromium "$work/dom.log" --dump-dom "file://$page#t=$time" > "$work/dom.html"
run_chromium "$work/screenshot.log" --screenshot="$work/view.png" "file://$page#t=$time" > /dev/null

python3 "$here/check_page.py" --dom "$work/dom.html" --expected "$expected" --time "$time" \
  --screenshot "$work/view.png" --logs "$work/dom.log" "$work/screenshot.log" ${caption:+--caption "$caption"}

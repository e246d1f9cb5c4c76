#!/usr/bin/env bash
# Browser check of `nec serve`: starts the studio on a free loopback port, drives headless Chromium through its
# page with puppeteer-core (check_studio.mjs: upload a rig, generate, watch it play, download the BVH), reads the
# download back with nec, stops the studio and checks that its work folder is gone.
#
#   tests/browser/studio/check_studio.sh NEC_BINARY WORKDIR
#
# Exit status: 0 passed, 1 a check failed, 77 (CTest: skipped) without chromium, node, puppeteer-core
# (scripts/test.sh installs it into tests/browser/studio/node_modules), three.js in nec, or the default models.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
[ $# -eq 2 ] || { echo "usage: $0 NEC_BINARY WORKDIR" >&2; exit 2; }
nec=$1 work=$2
chromium=${NEC_CHROMIUM:-chromium}
skip() { echo "studio browser check: skipped: $*"; exit 77; }
command -v "$chromium" >/dev/null || skip "$chromium is not installed (scripts/setup_viewer_assets.sh installs it)"
command -v node >/dev/null || skip "node is not installed"
[ -d "$here/node_modules/puppeteer-core" ] || skip "puppeteer-core is not installed (npm ci --prefix tests/browser/studio)"
[ -f "$root/models/default/gpt/config.json" ] || skip "no default models"

rm -rf "$work" && mkdir -p "$work/studio"
"$nec" zoo --out "$work/zoo" --plans biped --creatures 1 --clips-per-creature 1 --seconds 1 --seed 2 --quiet
rig=$(find "$work/zoo" -name '*.bvh' | head -n 1)
# The studio's page plays motion with the three.js nec embeds when it is built: without it there is nothing to see.
if ! "$nec" view "$rig" -o "$work/three_probe.html" > "$work/three_probe.log" 2>&1; then
  grep -q "built without three.js" "$work/three_probe.log" && skip "this nec was built without three.js"
  cat "$work/three_probe.log" >&2
  exit 1
fi
: > "$work/serve.log"  # there before the loop below reads it: the background job opens it when it gets to run
"$nec" serve --port 0 --work "$work/studio" --threads 1 > "$work/serve.log" 2>&1 &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
url=""
for _ in $(seq 100); do
  url=$(sed -nE 's#^nec studio on (http://[^ ]+) .*#\1#p' "$work/serve.log")
  [ -n "$url" ] && break
  kill -0 $server 2>/dev/null || { cat "$work/serve.log" >&2; exit 1; }
  sleep 0.1
done
[ -n "$url" ] || { echo "studio: nec serve did not start:" >&2; cat "$work/serve.log" >&2; exit 1; }
echo "studio: $url"
NEC_CHROMIUM=$(command -v "$chromium") node "$here/check_studio.mjs" "$url" "$rig" "$work"
"$nec" info --no-tree "$work/downloaded.bvh" > "$work/downloaded.info"
echo "studio: ok: nec reads the downloaded BVH back ($(grep -E '^joints' "$work/downloaded.info"))"
kill -TERM $server
wait $server
trap - EXIT
if [ -n "$(ls -A "$work/studio")" ]; then
  echo "studio: FAILED: the work folder was not removed: $(ls -A "$work/studio")" >&2
  exit 1
fi
echo "studio: ok: stopped, its work folder removed"

#!/usr/bin/env bash
# Fetches the three.js files that `nec view` inlines into its HTML pages and,
# unless NEC_NO_BROWSER=1, installs Debian's chromium for the browser test
# (CTest label `browser`). Idempotent; scripts/setup.sh runs it before building.
#
#   scripts/setup_viewer_assets.sh
#
# The npm package three@0.170.0 (the last release whose build/ holds a single
# minified ES module, three.module.min.js: 0.69 MB, where 0.171+ split it in two
# and benchmarks/ pins 0.187.0 with 2.1 MB of unminified modules) is packed
# with `npm pack`, checked against the pinned SHA-512 (npm's dist.integrity)
# and unpacked into the git-ignored third_party_cache/three-0.170.0/. CMake
# embeds these files from there into the nec binary at build time
# (viewer/CMakeLists.txt):
#   build/three.module.min.js, examples/jsm/loaders/BVHLoader.js,
#   examples/jsm/loaders/GLTFLoader.js (+ utils/BufferGeometryUtils.js, which it
#   imports: rigged assets show their skinned mesh),
#   examples/jsm/controls/OrbitControls.js   (+ LICENSE, three.js is MIT)
set -euo pipefail
cd "$(dirname "$0")/.."

version=0.170.0
# npm view three@0.170.0 dist.integrity, in hex
sha512=1502be2c4a587347c10fe27c83aa12132c8dce3a7e43b2acd42e7af1659aa0c44b5be4e434d5a67a759e1a0263575d3919dfa9ff6aa5d5972362f3623d9061b9
dest=third_party_cache/three-$version
files=(build/three.module.min.js examples/jsm/loaders/BVHLoader.js examples/jsm/loaders/GLTFLoader.js
       examples/jsm/utils/BufferGeometryUtils.js examples/jsm/controls/OrbitControls.js LICENSE)

source scripts/lib.sh

have_all=1
for f in "${files[@]}"; do [ -f "$dest/$f" ] || have_all=0; done
if [ $have_all = 0 ]; then
  ensure_packages setup_viewer_assets nodejs npm
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  (cd "$work" && npm pack "three@$version" --silent >/dev/null)
  tarball="$work/three-$version.tgz"
  actual=$(sha512sum "$tarball" | cut -d' ' -f1)
  if [ "$actual" != "$sha512" ]; then
    echo "setup_viewer_assets: three-$version.tgz has SHA-512 $actual, expected $sha512" >&2
    exit 1
  fi
  mkdir -p "$work/unpacked"
  tar -xzf "$tarball" -C "$work/unpacked" "${files[@]/#/package/}"
  rm -rf "$dest"
  mkdir -p "$(dirname "$dest")"
  mv "$work/unpacked/package" "$dest"
  echo "setup_viewer_assets: three.js $version -> $dest"
fi

if [ "${NEC_NO_BROWSER:-0}" != 1 ]; then
  ensure_packages setup_viewer_assets chromium
fi

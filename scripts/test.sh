#!/usr/bin/env bash
# Sets up, builds and runs every test. Extra arguments go to ctest, e.g. -L unit.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# three.js for the interop test's three.js half (without it that half is skipped).
source scripts/lib.sh
ensure_three || echo "test: three.js not installed; interop_import skips its three.js half"
# The sentence encoder's own runner, the reference test_sentence_encoder checks nec against.
ensure_packages test nodejs npm
# Blender (and the numpy its glTF importer needs), for the add-on and interop tests (ctest -L interop): without
# it they skip.
ensure_packages test blender python3-numpy
[ -d tests/sentence_encoder/node_modules/@energetic-ai/embeddings ] ||
  npm ci --prefix tests/sentence_encoder --no-audit --no-fund
# puppeteer-core, which drives Debian's chromium through the studio page (tests/browser/studio).
[ -d tests/browser/studio/node_modules/puppeteer-core ] ||
  npm ci --prefix tests/browser/studio --no-audit --no-fund
cd build
ctest --output-on-failure --parallel "$(nproc)" "$@"

#!/usr/bin/env bash
# Sets up, builds and runs every test. Extra arguments go to ctest, e.g. -L unit.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
# three.js for the interop test's three.js half (without it that half is skipped).
source scripts/lib.sh
ensure_three || echo "test: three.js not installed; interop_import skips its three.js half"
cd build
ctest --output-on-failure --parallel "$(nproc)" "$@"

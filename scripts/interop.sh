#!/usr/bin/env bash
# Installs Blender (Debian's 3.4), node + three.js and the CMU test files when
# missing, builds nec in build-interop/ and runs the interop check
# (CTest label `interop`): BVH written by nec must import in Blender and in
# three.js BVHLoader as nec reads it (tests/interop/check_import.sh), and the
# Blender add-on must work inside Blender (tests/blender/check_addon.sh).
#   scripts/interop.sh
set -euo pipefail
cd "$(dirname "$0")/.."

source scripts/lib.sh
ensure_packages interop cmake ninja-build libeigen3-dev nlohmann-json3-dev libfmt-dev libgtest-dev libgmock-dev libassimp-dev blender python3-numpy nodejs npm assimp-testmodels
ensure_three

cmake -S . -B build-interop -G Ninja -DCMAKE_BUILD_TYPE=Release -DNEC_BUILD_TESTS=ON >/dev/null
cmake --build build-interop --target nec
ctest --test-dir build-interop -L interop --output-on-failure

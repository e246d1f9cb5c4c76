#!/usr/bin/env bash
# Builds the libFuzzer target for the BVH reader (clang, ASan + UBSan) in
# build-fuzz/ and runs it.
#   scripts/fuzz.sh [SECONDS]        # default 600
# Seeds: tests/fuzz/corpus (hand-written) plus trimmed copies of the real BVH
# files (CMU from assimp-testmodels, ../shared/data), made in a temporary
# directory under /tmp and deleted afterwards; the real files never enter the
# repository. New inputs go to build-fuzz/corpus, crashes to build-fuzz/artifacts,
# the log to build-fuzz/fuzz.log. Exit status: the fuzzer's (0 = nothing found).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
max_len=65536

source scripts/lib.sh
ensure_packages fuzz clang libclang-rt-14-dev cmake ninja-build libeigen3-dev nlohmann-json3-dev libfmt-dev

CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DNEC_BUILD_FUZZERS=ON -DNEC_BUILD_TESTS=OFF >/dev/null
cmake --build build-fuzz --target fuzz_bvh

# Real files, each cut to its hierarchy and as many whole frames as fit in
# max_len (with "Frames:" corrected, CRLF made LF), so that the seeds are valid BVH.
seeds=$(mktemp -d /tmp/nec-fuzz-seeds.XXXXXX)
trap 'rm -rf "$seeds"' EXIT
real_files=(/usr/share/assimp/models/BVH/*.bvh)
shared=../shared/data
if [ -d "$shared" ]; then
  mapfile -t -O ${#real_files[@]} real_files < <(
    find "$shared/mann_dog" -name '*.bvh' 2>/dev/null | sort | head -n 3
    find "$shared/bandai" -name '*.bvh' 2>/dev/null | sort | head -n 3)
fi
for f in "${real_files[@]}"; do
  [ -f "$f" ] || continue
  awk -v budget=$((max_len - 256)) '
    { sub(/\r$/, "") }
    state == 0 { header = header $0 "\n"; if ($1 == "MOTION") state = 1; next }
    state == 1 && /Frames:/ { state = 2; next }
    state == 2 { frame_time = $0; state = 3; used = length(header) + length(frame_time) + 32; next }
    state == 3 { if (used + length($0) + 1 > budget) exit; lines[n++] = $0; used += length($0) + 1 }
    END {
      printf "%sFrames: %d\n%s\n", header, n, frame_time
      for (i = 0; i < n; ++i) print lines[i]
    }' "$f" > "$seeds/$(basename "$f")"
done
echo "fuzz: $(ls "$seeds" | wc -l) seeds from real files in $seeds"

mkdir -p build-fuzz/corpus build-fuzz/artifacts
set +e
build-fuzz/tests/fuzz/fuzz_bvh \
  -max_len=$max_len -timeout=5 -max_total_time="$seconds" -print_final_stats=1 \
  -dict=tests/fuzz/bvh.dict -artifact_prefix=build-fuzz/artifacts/ \
  build-fuzz/corpus tests/fuzz/corpus "$seeds" 2>&1 | tee build-fuzz/fuzz.log
status=${PIPESTATUS[0]}
set -e
if [ "$status" -ne 0 ]; then
  echo "fuzz: the fuzzer stopped with status $status; reproducer(s) in build-fuzz/artifacts:" >&2
  ls -la build-fuzz/artifacts >&2
fi
exit "$status"

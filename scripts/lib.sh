# Shared shell helpers for the scripts in this folder (source it, don't run it).

# ensure_packages LABEL PACKAGE...: apt-get installs the Debian packages that
# are missing (run as root, or with sudo available). `npm` counts as present
# when an npm command exists (nodesource's nodejs ships its own).
ensure_packages() {
  local label=$1 p
  shift
  local missing=()
  for p in "$@"; do
    if [ "$p" = npm ] && command -v npm >/dev/null; then continue; fi
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "$label: installing ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# ensure_three: three.js (pinned in benchmarks/package.json) for the peer
# benchmark, the interop check and the viewer.
ensure_three() {
  if [ ! -f benchmarks/node_modules/three/examples/jsm/loaders/BVHLoader.js ]; then
    npm install --prefix benchmarks --no-audit --no-fund
  fi
}

# fetch_npm_tarball LABEL PACKAGE VERSION SHA512 TARBALL: `npm pack`s PACKAGE@VERSION
# into TARBALL unless a file with that SHA-512 (npm's dist.integrity, in hex) is
# there already; a download with another checksum stops the script.
fetch_npm_tarball() {
  local label=$1 package=$2 version=$3 sha512=$4 tarball=$5 work packed
  if [ -f "$tarball" ] && [ "$(sha512sum "$tarball" | cut -d' ' -f1)" = "$sha512" ]; then return 0; fi
  ensure_packages "$label" nodejs npm
  mkdir -p "$(dirname "$tarball")"
  work=$(mktemp -d "$(dirname "$tarball")/.npm-pack.XXXXXX")
  echo "$label: downloading $package@$version with npm pack"
  if ! (cd "$work" && npm pack "$package@$version" --silent >/dev/null); then
    rm -rf "$work"
    echo "$label: npm pack $package@$version failed" >&2
    return 1
  fi
  packed=$(ls "$work"/*.tgz)
  if [ "$(sha512sum "$packed" | cut -d' ' -f1)" != "$sha512" ]; then
    echo "$label: $(basename "$packed") has SHA-512 $(sha512sum "$packed" | cut -d' ' -f1), expected $sha512" >&2
    rm -rf "$work"
    return 1
  fi
  mv "$packed" "$tarball"
  rm -rf "$work"
  echo "$label: $package $version -> $tarball"
}

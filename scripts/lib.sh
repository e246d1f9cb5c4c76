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

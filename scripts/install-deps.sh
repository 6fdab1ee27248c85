#!/usr/bin/env bash
# Installs every build and run-time dependency of svbtdf from Debian 12 packages.
# Idempotent: packages already present are left alone, so running it twice is harmless.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config python3
  libeigen3-dev libceres-dev
  libmetis-dev   # the fill-reducing ordering of the NDF fit's sparse solves (fit/src/texel_fit.cc)
  libblas3 liblapack3   # the reference BLAS and LAPACK svbtdf loads (cmake/ReferenceLinearAlgebra.cmake)
  libopencv-dev
  libopenimageio-dev openimageio-tools libopenexr-dev libpng-dev zlib1g-dev
  libcamera-dev linux-libc-dev libv4l-dev
  libgphoto2-dev libsdl2-dev libjpeg-dev libx11-dev
  xvfb x11-apps   # the SDL display tested in a real X11 window (tests/acquire/sdl_display_test.cc)
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  blender   # tests/export's Blender check and the demo's Blender picture (docs/export.md)
  chromium  # tests/report's browser test drives it headless (docs/report.md); WebGL through SwiftShader
  pybind11-dev python3-dev python3-numpy python3-pytest
  clang-14 libclang-rt-14-dev   # scripts/sanitize.sh: AddressSanitizer, UBSan and libFuzzer (docs/testing.md)
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive

install_packages() {
  echo "svbtdf: installing $#: $*"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "$@"
}

if [ ${#missing[@]} -eq 0 ]; then
  echo "svbtdf: all ${#PACKAGES[@]} dependencies already installed"
else
  install_packages "${missing[@]}"
fi

# The pinned npm tools, each folder's versions in its package-lock.json: node from Debian when
# this machine has none, then `npm ci` (and the folder's bundle step, if it has one), again only
# when the lock changed. tools/gltf: the Khronos glTF-Validator (tests/export). tools/report:
# three.js bundled into one classic script for the report page, and puppeteer-core for its
# browser test (never a browser download: it drives Debian's chromium).
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then install_packages nodejs npm; fi
install_npm_tools() {
  local folder="$(cd "$(dirname "$0")/.." && pwd)/tools/$1"
  local stamp="$folder/node_modules/.svbtdf-package-lock.json"  # the lock that was installed
  if cmp -s "$folder/package-lock.json" "$stamp" 2>/dev/null && { [ -z "${2:-}" ] || [ -e "$folder/$2" ]; }; then return; fi
  echo "svbtdf: installing the pinned npm tools of tools/$1 (npm ci)"
  (cd "$folder" && PUPPETEER_SKIP_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
  if [ -n "${2:-}" ]; then (cd "$folder" && npm run --silent bundle >/dev/null); fi
  cp "$folder/package-lock.json" "$stamp"
}
install_npm_tools gltf
install_npm_tools report dist/three-bundle.js

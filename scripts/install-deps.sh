#!/usr/bin/env bash
# Installs every build and run-time dependency of svbtdf from Debian 12 packages.
# Idempotent: packages already present are left alone, so running it twice is harmless.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config python3
  libeigen3-dev libceres-dev
  libblas3 liblapack3   # the reference BLAS and LAPACK svbtdf loads (cmake/ReferenceLinearAlgebra.cmake)
  libopencv-dev
  libopenimageio-dev openimageio-tools libopenexr-dev libpng-dev zlib1g-dev
  libcamera-dev linux-libc-dev libv4l-dev
  libgphoto2-dev libsdl2-dev libjpeg-dev libx11-dev
  xvfb x11-apps   # the SDL display tested in a real X11 window (tests/acquire/sdl_display_test.cc)
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  blender   # tests/export's Blender check and the demo's Blender picture (docs/export.md)
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

# The Khronos glTF-Validator (tests/export), pinned in tools/gltf/package-lock.json: node from
# Debian when this machine has none, then `npm ci`, again only when the lock changed.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then install_packages nodejs npm; fi
GLTF_TOOLS="$(cd "$(dirname "$0")/.." && pwd)/tools/gltf"
STAMP="$GLTF_TOOLS/node_modules/.svbtdf-package-lock.json"  # the lock that was installed
if ! cmp -s "$GLTF_TOOLS/package-lock.json" "$STAMP" 2>/dev/null; then
  echo "svbtdf: installing the pinned glTF-Validator (npm ci in tools/gltf)"
  (cd "$GLTF_TOOLS" && npm ci --no-audit --no-fund --loglevel=error)
  cp "$GLTF_TOOLS/package-lock.json" "$STAMP"
fi

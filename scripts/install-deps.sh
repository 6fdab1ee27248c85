#!/usr/bin/env bash
# Installs every build and run-time dependency of svbtdf from Debian 12 packages.
# Idempotent: packages already present are left alone, so running it twice is harmless.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config python3
  libeigen3-dev libceres-dev
  libopencv-dev
  libopenimageio-dev openimageio-tools libopenexr-dev libpng-dev zlib1g-dev
  libcamera-dev linux-libc-dev libv4l-dev
  libgphoto2-dev libsdl2-dev libjpeg-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  pybind11-dev python3-dev python3-numpy python3-pytest
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "svbtdf: all ${#PACKAGES[@]} dependencies already installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "svbtdf: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"

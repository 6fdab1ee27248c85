#!/usr/bin/env bash
# Builds svbtdf and runs its default test suite (everything but the "slow" label).
#   scripts/test.sh            default suite (well under 15 minutes on 2 cores)
#   scripts/test.sh -L slow    the paper-scale tests only (any ctest arguments pass through)
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
BUILD_DIR=${SVBTDF_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" --parallel "$(nproc)"

if [ $# -eq 0 ]; then set -- -LE slow; fi
ctest --test-dir "$BUILD_DIR" --output-on-failure --parallel "$(nproc)" --timeout 900 "$@"

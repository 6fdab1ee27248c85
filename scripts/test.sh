#!/usr/bin/env bash
# Builds svbtdf and runs its default test suite (everything but the "slow" label).
#   scripts/test.sh            default suite (well under 15 minutes on 2 cores)
#   scripts/test.sh -L slow    the paper-scale tests only (any ctest arguments pass through)
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
# The layers of docs/architecture.md, before building (python3 comes with install-deps.sh).
# Two commands, not `a && b`: under set -e a failing `a` in an && list would not stop the script.
python3 scripts/check_layers.py --self-test
python3 scripts/check_layers.py
BUILD_DIR=${SVBTDF_BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" --parallel "$(nproc)"

if [ $# -eq 0 ]; then set -- -LE slow; fi
ctest --test-dir "$BUILD_DIR" --output-on-failure --parallel "$(nproc)" --timeout 900 "$@"

#!/usr/bin/env bash
# The main job on the simulated rig: installs what is needed, builds svbtdf, and runs the
# model validation against a Monte Carlo ground truth, writing figures and an HTML report.
# Results go to out/demo/ (override with SVBTDF_DEMO_OUT).
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
BUILD_DIR=${SVBTDF_BUILD_DIR:-build}
OUT=${SVBTDF_DEMO_OUT:-out/demo}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" --parallel "$(nproc)" --target svbtdf
SVBTDF="$BUILD_DIR/cli/svbtdf"

mkdir -p "$OUT"
"$SVBTDF" validate-model --json "$OUT/validation.json" --plots "$OUT/report"

echo
echo "svbtdf demo finished."
echo "  model validation (JSON):  $OUT/validation.json"
echo "  report (open in a browser): $OUT/report/index.html"

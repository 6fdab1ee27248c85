#!/usr/bin/env bash
# The main job on the simulated rig: installs what is needed, builds svbtdf, simulates a capture
# session of a known material (what a lab capture writes), calibrates, processes and fits it,
# compares the fitted material with the truth, validates the BTDF model against a Monte Carlo
# slab, and writes an HTML report. Results go to out/demo/ (SVBTDF_DEMO_OUT overrides);
# a previous demo there is moved aside, never overwritten.
set -euo pipefail
cd "$(dirname "$0")/.."

bash scripts/install-deps.sh
BUILD_DIR=${SVBTDF_BUILD_DIR:-build}
OUT=${SVBTDF_DEMO_OUT:-out/demo}
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" --parallel "$(nproc)" --target svbtdf
SVBTDF="$BUILD_DIR/cli/svbtdf"

if [ -e "$OUT" ]; then
  mv "$OUT" "$OUT.previous-$(date +%Y%m%d-%H%M%S)"
fi
mkdir -p "$OUT"

echo "== 1/7 simulating a capture session of the 'demo' material (a few minutes)"
"$SVBTDF" simulate --preset demo --out "$OUT/simulated"

echo "== 2/7 calibrating, processing and fitting the session (svbtdf run)"
"$SVBTDF" run "$OUT/simulated/session" --out "$OUT/material" --holdout 0.1

echo "== 3/7 comparing the fitted material with the ground truth"
"$SVBTDF" compare "$OUT/material" "$OUT/simulated/truth" --json "$OUT/compare.json"

echo "== 4/7 rendering the fitted material beside its truth, from a view the rig never saw"
mkdir -p "$OUT/render"
render_views=("0 0" "25 90")
for k in 0 1; do
  view=${render_views[$k]}
  render=(--view-deg $view --resolution 256 256 --distance 0.3 --fov-deg 20 --background-distance 0.03 --checker-size 0.005)
  "$SVBTDF" render "$OUT/simulated/truth" "${render[@]}" --spp 128 --out "$OUT/render/view$k-truth.exr" \
    --png "$OUT/render/view$k-truth.png" --json "$OUT/render/view$k-truth.json"
  # The truth again with another seed: how much of the difference below is Monte Carlo noise.
  "$SVBTDF" render "$OUT/simulated/truth" "${render[@]}" --spp 128 --seed 2 --out "$OUT/render/view$k-truth-seed2.exr" \
    --compare-to "$OUT/render/view$k-truth.exr" --json "$OUT/render/view$k-noise.json"
  "$SVBTDF" render "$OUT/material" "${render[@]}" --spp 64 --out "$OUT/render/view$k-material.exr" \
    --png "$OUT/render/view$k-material.png" --compare-to "$OUT/render/view$k-truth.exr" --json "$OUT/render/view$k.json"
done

echo "== 5/7 exporting the fitted material as glTF 2.0 (docs/export.md)"
"$SVBTDF" export "$OUT/material" --gltf "$OUT/gltf"
if command -v blender >/dev/null; then
  # Blender's picture of the export: Cycles, head-on, 2 cm in front of a checkerboard.
  blender -b --factory-startup --python tools/blender/render_export.py -- --gltf "$OUT/gltf/material.gltf" \
    --png "$OUT/gltf/blender.png" --json "$OUT/gltf/blender.json" > "$OUT/gltf/blender.log" 2>&1 ||
    echo "warning: demo: Blender could not render the export (see $OUT/gltf/blender.log)" >&2
fi

echo "== 6/7 validating the dual-microfacet model against a Monte Carlo slab (about two minutes)"
"$SVBTDF" validate-model --json "$OUT/validation.json" --plots "$OUT/validation"

echo "== 7/7 the report: the material live, its slices, maps, numbers, calibration and capture (docs/report.md)"
"$SVBTDF" report "$OUT/material" --out "$OUT/report" --truth "$OUT/simulated/truth" --compare "$OUT/compare.json" \
  --renders "$OUT/render" --gltf "$OUT/gltf/material.gltf" --validation "$OUT/validation/index.html"

metric() { sed -n "s/.*\"$1\": *\([^,}]*\).*/\1/p" "$OUT/compare.json" | head -1; }
echo
echo "svbtdf demo finished."
echo "  simulated session:  $OUT/simulated/session   (truth: $OUT/simulated/truth)"
echo "  model validation:   $OUT/validation.json"
echo "  fitted material:    $OUT/material"
echo "  glTF export:        $OUT/gltf/material.gltf"
echo "  error against the truth: held-out BTDF relative RMSE $(metric heldout_rel_rmse)," \
     "alpha within 0.05 on a fraction $(metric alpha_within_0_05) of texels," \
     "NDF relative L2 median $(metric ndf_rel_l2_median)  (all metrics: $OUT/compare.json)"
echo
echo "report: $(cd "$OUT/report" && pwd)/index.html   (open it in a browser; it works from file://)"

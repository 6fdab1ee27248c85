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

echo "== 4/7 pictures of the material beside the truth"
"$SVBTDF" report "$OUT/material" --out "$OUT/material-report" --truth "$OUT/simulated/truth" --compare "$OUT/compare.json"

echo "== 5/7 rendering the fitted material beside its truth, from a view the rig never saw"
mkdir -p "$OUT/render"
render_views=("0 0" "25 90")
for k in 0 1; do
  view=${render_views[$k]}
  render=(--view-deg $view --resolution 256 256 --distance 0.3 --fov-deg 20 --background-distance 0.03 --checker-size 0.005)
  "$SVBTDF" render "$OUT/simulated/truth" "${render[@]}" --spp 128 --out "$OUT/render/view$k-truth.exr" \
    --png "$OUT/render/view$k-truth.png"
  # The truth again with another seed: how much of the difference below is Monte Carlo noise.
  "$SVBTDF" render "$OUT/simulated/truth" "${render[@]}" --spp 128 --seed 2 --out "$OUT/render/view$k-truth-seed2.exr" \
    --compare-to "$OUT/render/view$k-truth.exr" --json "$OUT/render/view$k-noise.json"
  "$SVBTDF" render "$OUT/material" "${render[@]}" --spp 64 --out "$OUT/render/view$k-material.exr" \
    --png "$OUT/render/view$k-material.png" --compare-to "$OUT/render/view$k-truth.exr" --json "$OUT/render/view$k.json"
done

echo "== 6/7 exporting the fitted material as glTF 2.0 (docs/export.md)"
"$SVBTDF" export "$OUT/material" --gltf "$OUT/gltf"
if command -v blender >/dev/null; then
  # Blender's picture of the export: Cycles, head-on, 2 cm in front of a checkerboard.
  blender -b --factory-startup --python tools/blender/render_export.py -- --gltf "$OUT/gltf/material.gltf" \
    --png "$OUT/gltf/blender.png" --json "$OUT/gltf/blender.json" > "$OUT/gltf/blender.log" 2>&1 ||
    echo "warning: demo: Blender could not render the export (see $OUT/gltf/blender.log)" >&2
fi

echo "== 7/7 validating the dual-microfacet model against a Monte Carlo slab (about a minute)"
"$SVBTDF" validate-model --json "$OUT/validation.json" --plots "$OUT/validation"

# A small report page: the simulated images next to the model validation.
mkdir -p "$OUT/images"
for key in board/v00 sample_plane/v00 all_dots/e0 fiducials/e0 dot/q0010/e1/r0; do
  name=$(echo "$key" | tr / _)
  source="$OUT/simulated/session/images/$key.png"
  # Camera values fill only the sensor's bit depth: stretch the brightest to white, gamma 2.2.
  max=$(oiiotool --stats "$source" | awk '/Stats Max/ {m=$3; for (i=4;i<=5;i++) if ($i>m) m=$i; print m; exit}')
  oiiotool "$source" --mulc "$(awk -v m="${max:-65535}" 'BEGIN {print (m > 0 ? 65535 / m : 1)}')" --powc 0.4545 \
    -d uint8 -o "$OUT/images/$name.png"
done
images=$(grep -c '"key"' "$OUT/simulated/session/journal.jsonl")
render_metrics() { sed -n 's/.*"\(relative_rmse\|ssim\)": *\([^,}]*\).*/\1 \2/p' "$1" | tr '\n' ' '; }
cat > "$OUT/index.html" <<HTML
<!doctype html><html><head><meta charset="utf-8"><title>svbtdf demo report</title>
<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}img{max-width:260px;margin:4px;border:1px solid #ccc}</style>
</head><body>
<h1>svbtdf demo report</h1>
<h2>1. Simulated capture session</h2>
<p>$images images in <code>simulated/session</code> (format: docs/session-format.md), ground truth in
<code>simulated/truth</code>. A calibration board view, the board in the sample holder, all dots, the fiducial dots (which tell calibration which dot is which and which way up the monitor lies), and one dot seen through the sample:</p>
<p><img src="images/board_v00.png"><img src="images/sample_plane_v00.png"><img src="images/all_dots_e0.png"><img src="images/fiducials_e0.png"><img src="images/dot_q0010_e1_r0.png"></p>
<h2>2. The fitted material</h2>
<p><code>svbtdf run</code> calibrated the session (<code>simulated/session/calibration.json</code>), processed it into
per-texel BTDF samples and fitted the dual-microfacet material <code>material/</code> (format: docs/material-format.md),
withholding 10% of the dots. Its maps and NDFs beside the ground truth, and its errors:
<a href="material-report/index.html">material-report/index.html</a>.</p>
<pre>$(cat "$OUT/compare.json")</pre>
<h2>3. The fitted material rendered beside its truth</h2>
<p><code>svbtdf render</code> (docs/render.md): the sample 3 cm in front of a checkerboard of 5 mm squares, seen
head-on and from 25 degrees on a side the rig's camera never looked from. Left the truth, right the fitted material;
relative RMSE and SSIM of the material's image against the truth's, and of the truth's against itself rendered with
another seed: at these sample counts most of the difference is Monte Carlo noise (docs/validation.md, "Novel views
against the truth", takes the noise out: the demo material is within 2% of its truth at every view).</p>
<table><tr><th>view (theta, phi)</th><th>truth</th><th>fitted material</th></tr>
<tr><td>0, 0</td><td><img src="render/view0-truth.png"></td><td><img src="render/view0-material.png"><br>$(render_metrics "$OUT/render/view0.json")<br>truth, another seed: $(render_metrics "$OUT/render/view0-noise.json")</td></tr>
<tr><td>25, 90</td><td><img src="render/view1-truth.png"></td><td><img src="render/view1-material.png"><br>$(render_metrics "$OUT/render/view1.json")<br>truth, another seed: $(render_metrics "$OUT/render/view1-noise.json")</td></tr>
</table>
<h2>4. The material exported to glTF 2.0</h2>
<p><code>svbtdf export</code> (docs/export.md) wrote <code>gltf/material.gltf</code>: every texel's NDF as an anisotropic
GGX lobe, with the Khronos transmission, volume, IOR, anisotropy and diffuse-transmission extensions.
$( [ -e "$OUT/gltf/blender.png" ] && echo 'Blender 3.4 imported it and rendered it with Cycles in front of a checkerboard (it ignores the anisotropy and the diffuse transmission):</p><p><img src="gltf/blender.png">' || echo '(Blender is not installed: no picture.)')</p>
<pre>$(cat "$OUT/gltf/material.export.json")</pre>
<h2>5. The dual-microfacet model against a Monte Carlo slab</h2>
<p>Relative L2 errors of the model and of single-interface baselines, with plane-of-incidence plots:
<a href="validation/index.html">validation/index.html</a> (docs/validation.md explains the cases).</p>
</body></html>
HTML

metric() { sed -n "s/.*\"$1\": *\([^,}]*\).*/\1/p" "$OUT/compare.json" | head -1; }
echo
echo "svbtdf demo finished."
echo "  simulated session:  $OUT/simulated/session   (truth: $OUT/simulated/truth)"
echo "  model validation:   $OUT/validation.json"
echo "  report:             $OUT/index.html"
echo "  fitted material:    $OUT/material"
echo "  glTF export:        $OUT/gltf/material.gltf"
echo "  error against the truth: held-out BTDF relative RMSE $(metric heldout_rel_rmse)," \
     "alpha within 0.05 on a fraction $(metric alpha_within_0_05) of texels," \
     "NDF relative L2 median $(metric ndf_rel_l2_median)  (all metrics: $OUT/compare.json)"

#!/usr/bin/env bash
# Novel views against the truth (docs/validation.md, "Novel views against the truth"): simulates
# a session, fits it with the dual-microfacet model and the ggx baseline, renders the truth and
# both fits in the background scene at the capture view and at two views the rig never saw, and
# scores each rendering against the truth's (relative RMSE, SSIM). Writes OUT/index.html with the
# pictures side by side and OUT/summary.md with the numbers.
#
#   scripts/validate_render.sh OUT "SIMULATE OPTIONS"     e.g.
#   scripts/validate_render.sh out/novel-demo "--preset demo"
#   scripts/validate_render.sh out/novel-mc "--preset small --truth montecarlo"
#
# SVBTDF (the program, default build/cli/svbtdf), RESOLUTION (64), SPP (2048; the truth gets 2x).
#
# Monte Carlo noise: every image is rendered twice (seeds 1 and 2), so that each image's noise is
# known (sigma^2 = RMSE(seed 1, seed 2)^2 / 2) and the table also gives the error with the noise
# of both images taken out, sqrt(RMSE^2 - sigma_fit^2 - sigma_truth^2): the fit's own error.
set -euo pipefail
OUT=${1:?usage: validate_render.sh OUT "SIMULATE OPTIONS"}
SIMULATE_OPTIONS=${2:-"--preset demo"}
SVBTDF=${SVBTDF:-build/cli/svbtdf}
RESOLUTION=${RESOLUTION:-64}
SPP=${SPP:-2048}
mkdir -p "$OUT"

[ -e "$OUT/simulated/truth/material.json" ] || "$SVBTDF" simulate $SIMULATE_OPTIONS --out "$OUT/simulated"
[ -e "$OUT/dual/material.json" ] || "$SVBTDF" run "$OUT/simulated/session" --out "$OUT/dual" --holdout 0.1
[ -e "$OUT/ggx/material.json" ] || "$SVBTDF" fit "$OUT/dual.work/processed" --model ggx --holdout 0.1 --out "$OUT/ggx"
# The paper's fixed NDF horizon beside the default free one (docs/fitting.md, "Horizon").
[ -e "$OUT/dual-fixed/material.json" ] ||
  "$SVBTDF" fit "$OUT/dual.work/processed" --fixed-horizon --holdout 0.1 --out "$OUT/dual-fixed"

# The capture view (the camera's direction from the sample centre), the far side at 0 and 25
# degrees, and a field of view that frames the sample at the capture's distance.
read -r CAPTURE_THETA CAPTURE_PHI DISTANCE FOV < <(python3 - "$OUT/simulated/truth/rig.json" <<'PY'
import json, math, sys
rig = json.load(open(sys.argv[1]))
x, y, z = rig["camera"]["centre"]
d = math.sqrt(x * x + y * y + z * z)
theta = math.degrees(math.acos(z / d))
phi = math.degrees(math.atan2(y, x))
width = rig["sample"]["width"]
print(f"{theta:.3f} {phi:.3f} {d:.4f} {2 * math.degrees(math.atan(0.65 * width / d)):.3f}")
PY
)
FAR_PHI=$(python3 -c "print(($CAPTURE_PHI + 180) % 360)")
VIEWS=("capture:$CAPTURE_THETA $CAPTURE_PHI" "normal:0 0" "far-25:25 $FAR_PHI")
common=(--distance "$DISTANCE" --fov-deg "$FOV" --resolution "$RESOLUTION" "$RESOLUTION" --background-distance 0.03
        --checker-size 0.005)

echo "| view | theta, phi (deg) | dual-microfacet RMSE (noise removed) | SSIM | ggx RMSE (noise removed) | SSIM | dual, fixed horizon RMSE (noise removed) | SSIM | noise of one truth image |" > "$OUT/summary.md"
echo "|---|---|---|---|---|---|---|---|---|" >> "$OUT/summary.md"
metric() { python3 -c "import json; print('%.4f' % json.load(open('$1'))['$2'])"; }
# sqrt(max(0, r^2 - r_model_seeds^2 / 2 - r_truth_seeds^2 / 2))
denoised() {
  python3 -c "import json, math; r = [json.load(open(f))['relative_rmse'] for f in ('$1', '$2', '$3')]; print('%.4f' % math.sqrt(max(0.0, r[0] ** 2 - r[1] ** 2 / 2 - r[2] ** 2 / 2)))"
}
rows=""
for entry in "${VIEWS[@]}"; do
  name=${entry%%:*}
  view=${entry#*:}
  "$SVBTDF" render "$OUT/simulated/truth" --view-deg $view "${common[@]}" --spp $((2 * SPP)) \
    --out "$OUT/$name-truth.exr" --png "$OUT/$name-truth.png"
  "$SVBTDF" render "$OUT/simulated/truth" --view-deg $view "${common[@]}" --spp $((2 * SPP)) --seed 2 \
    --out "$OUT/$name-truth-seed2.exr" --compare-to "$OUT/$name-truth.exr" --json "$OUT/$name-truth-seed2.json"
  cells=""
  for model in dual ggx dual-fixed; do
    "$SVBTDF" render "$OUT/$model" --view-deg $view "${common[@]}" --spp "$SPP" \
      --out "$OUT/$name-$model.exr" --png "$OUT/$name-$model.png" \
      --compare-to "$OUT/$name-truth.exr" --json "$OUT/$name-$model.json"
    "$SVBTDF" render "$OUT/$model" --view-deg $view "${common[@]}" --spp "$SPP" --seed 2 \
      --out "$OUT/$name-$model-seed2.exr" --compare-to "$OUT/$name-$model.exr" --json "$OUT/$name-$model-seed2.json"
    cells+=" $(metric "$OUT/$name-$model.json" relative_rmse) ($(denoised "$OUT/$name-$model.json" "$OUT/$name-$model-seed2.json" "$OUT/$name-truth-seed2.json")) | $(metric "$OUT/$name-$model.json" ssim) |"
  done
  truth_noise=$(python3 -c "import json; print('%.4f' % (json.load(open('$OUT/$name-truth-seed2.json'))['relative_rmse'] / 2 ** 0.5))")
  echo "| $name | $view |$cells $truth_noise |" >> "$OUT/summary.md"
  rows+="<tr><th>$name<br>($view)</th><td><img src=\"$name-truth.png\"></td><td><img src=\"$name-dual.png\"><br>RMSE $(metric "$OUT/$name-dual.json" relative_rmse), SSIM $(metric "$OUT/$name-dual.json" ssim)</td><td><img src=\"$name-ggx.png\"><br>RMSE $(metric "$OUT/$name-ggx.json" relative_rmse), SSIM $(metric "$OUT/$name-ggx.json" ssim)</td><td><img src=\"$name-dual-fixed.png\"><br>RMSE $(metric "$OUT/$name-dual-fixed.json" relative_rmse), SSIM $(metric "$OUT/$name-dual-fixed.json" ssim)</td></tr>"
done
cat > "$OUT/index.html" <<HTML
<!doctype html><html><head><meta charset="utf-8"><title>svbtdf novel views</title>
<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto}img{width:256px;image-rendering:pixelated}td,th{padding:4px;vertical-align:top;text-align:center}</style>
</head><body><h1>Novel views against the truth</h1>
<p><code>svbtdf simulate $SIMULATE_OPTIONS</code>, fitted with the dual-microfacet model, the ggx baseline and the dual-microfacet model with the paper's fixed NDF horizon
(<code>--holdout 0.1</code>), rendered with <code>svbtdf render</code> in the background scene
(checkerboard of 5 mm squares 3 cm behind the sample), ${RESOLUTION}x${RESOLUTION}, $SPP spp (truth $((2 * SPP))). Relative RMSE against the truth's image; in brackets with both images' Monte Carlo noise removed.</p>
<table><tr><th>view</th><th>truth</th><th>dual-microfacet fit</th><th>ggx baseline</th><th>dual-microfacet, fixed horizon</th></tr>$rows</table>
</body></html>
HTML
cat "$OUT/summary.md"

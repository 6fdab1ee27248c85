#!/usr/bin/env bash
# What the glTF export's lobes lose (docs/validation.md, "The export against the material"):
# exports MATERIAL (svbtdf export: the lobe fit's error distribution), then renders the material
# and its export's lobes (svbtdf render --parametric) in the background scene head-on and at 25
# degrees, each twice (seeds 1 and 2), and scores the lobes' image against the material's, with
# the Monte Carlo noise of both taken out: sqrt(RMSE^2 - sigma_lobes^2 - sigma_material^2), each
# sigma^2 = RMSE(seed 1, seed 2)^2 / 2 (as scripts/validate_render.sh). Appends a row per view to
# OUT/summary.md.
#
#   scripts/validate_export.sh MATERIAL OUT      SVBTDF (default build/cli/svbtdf), RESOLUTION (64), SPP (512)
set -euo pipefail
MATERIAL=${1:?usage: validate_export.sh MATERIAL OUT}
OUT=${2:?usage: validate_export.sh MATERIAL OUT}
SVBTDF=${SVBTDF:-build/cli/svbtdf}
RESOLUTION=${RESOLUTION:-64}
SPP=${SPP:-512}
mkdir -p "$OUT"

"$SVBTDF" export "$MATERIAL" --gltf "$OUT/gltf" --name export | tee "$OUT/export.txt"
# A field of view that frames the sample from 0.3 m.
FOV=$(python3 -c "import json, math; s = json.load(open('$MATERIAL/material.json'))['sample']; print('%.3f' % (2 * math.degrees(math.atan(0.65 * max(s['width_m'], s['height_m']) / 0.3))))")
common=(--distance 0.3 --fov-deg "$FOV" --resolution "$RESOLUTION" "$RESOLUTION" --spp "$SPP" --background-distance 0.03
        --checker-size 0.005)
rmse() { python3 -c "import json; print(json.load(open('$1'))['relative_rmse'])"; }
[ -e "$OUT/summary.md" ] || {
  echo "| material | view (theta, phi) | lobes vs material, RMSE | noise removed | SSIM | noise of one material image | lobe fit error median / p90 / max |" > "$OUT/summary.md"
  echo "|---|---|---|---|---|---|---|" >> "$OUT/summary.md"
}
errors=$(python3 -c "import json; e = json.load(open('$OUT/gltf/export.export.json'))['lobe_fit']['relative_error']; print('%.3f / %.3f / %.3f' % (e['median'], e['p90'], e['max']))")
for view in "0 0" "25 90"; do
  tag=$(echo "$view" | tr ' ' '-')
  for kind in material lobes; do
    flag=""; [ "$kind" = lobes ] && flag=--parametric
    "$SVBTDF" render "$MATERIAL" $flag --view-deg $view "${common[@]}" --seed 1 --out "$OUT/$kind-$tag-1.exr" \
      --png "$OUT/$kind-$tag-1.png" > /dev/null
    "$SVBTDF" render "$MATERIAL" $flag --view-deg $view "${common[@]}" --seed 2 --out "$OUT/$kind-$tag-2.exr" \
      --compare-to "$OUT/$kind-$tag-1.exr" --json "$OUT/$kind-$tag-noise.json" > /dev/null
  done
  "$SVBTDF" render "$MATERIAL" --parametric --view-deg $view "${common[@]}" --seed 2 --out "$OUT/lobes-$tag-2b.exr" \
    --compare-to "$OUT/material-$tag-1.exr" --json "$OUT/lobes-vs-material-$tag.json" > /dev/null
  python3 - "$OUT" "$tag" "$MATERIAL" "$view" "$errors" >> "$OUT/summary.md" <<'PY'
import json, math, sys
out, tag, material, view, errors = sys.argv[1:]
load = lambda name: json.load(open(f"{out}/{name}.json"))
r = load(f"lobes-vs-material-{tag}")
noise_lobes = load(f"lobes-{tag}-noise")["relative_rmse"]
noise_material = load(f"material-{tag}-noise")["relative_rmse"]
clean = math.sqrt(max(0.0, r["relative_rmse"] ** 2 - noise_lobes ** 2 / 2 - noise_material ** 2 / 2))
print(f"| {material} | {view.replace(' ', ', ')} | {r['relative_rmse']:.4f} | {clean:.4f} | {r['ssim']:.4f} | "
      f"{noise_material / math.sqrt(2):.4f} | {errors} |")
PY
done
cat "$OUT/summary.md"

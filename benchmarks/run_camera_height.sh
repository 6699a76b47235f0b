#!/usr/bin/env bash
# How much of a network's depth scale comes from the camera height (docs/dvso.md, session 35).
# A monocular network that reads depth from where the road meets an object in the image answers
# Z' = Z * h_assumed / h: its scale follows the camera height with elasticity -1. Each world below is
# rendered several times with only --camera-height changed (same seed: same streets, textures, light,
# cars), the model predicts on the colour images, and `dvso eval-depth` gives the median predicted /
# GT depth at textured pixels (image gradient >= 100, where DVSO selects points), over all pixels
# within MAX_DEPTH and at 40-80 m. Printed per world: the ratios per height and the elasticity
# d ln(ratio) / d ln(height) between the lowest and the highest camera (0: the height does not
# matter; -1: nothing but the height matters).
#
#   benchmarks/run_camera_height.sh [TRAJECTORY:FIRST:SEED ...]
#   env: DVSO=path/to/dvso (default build/dvso), MODEL=model.pt (default: the shipped one),
#        OUT=work dir (default /tmp/dvso_camera_height; rendered worlds are reused),
#        HEIGHTS="1.55 1.65 1.75" (m, before the varied look's own offset of up to +-0.1 m),
#        FRAMES=30, WIDTH=640, HEIGHT=192 (the training images' size), MAX_DEPTH=80
#   default worlds: the held-out trajectories of scripts/train_stacknet.sh (KITTI 08/09/10, their seeds; plain car
#   paint, --car-detail 0, as its default WORLDS=v4 renders them)
set -euo pipefail

REPO=$(cd "$(dirname "$0")/.." && pwd)
DVSO="${DVSO:-$REPO/build/dvso}"
MODEL="${MODEL:-$REPO/models/stacknet_cpu_main.pt}"
OUT="${OUT:-/tmp/dvso_camera_height}"
HEIGHTS="${HEIGHTS:-1.55 1.65 1.75}"
FRAMES="${FRAMES:-30}"
WIDTH="${WIDTH:-640}"
HEIGHT="${HEIGHT:-192}"
MAX_DEPTH="${MAX_DEPTH:-80}"
WORLDS=("$@")
[[ ${#WORLDS[@]} -gt 0 ]] || WORLDS=(08:1000:308 09:300:309 10:300:310)
[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
[[ -f "$MODEL" ]] || { echo "error: model $MODEL not found" >&2; exit 1; }
command -v python3 >/dev/null || { echo "error: python3 is needed to read the JSON metrics" >&2; exit 1; }
read -ra HEIGHT_LIST <<< "$HEIGHTS"
[[ ${#HEIGHT_LIST[@]} -ge 2 ]] || { echo "error: HEIGHTS needs at least two values" >&2; exit 1; }
mkdir -p "$OUT"
tag=$(basename "$MODEL" .pt)

for spec in "${WORLDS[@]}"; do
  IFS=: read -r trajectory first seed <<< "$spec"
  [[ -n "$seed" ]] || { echo "error: world '$spec' is not TRAJECTORY:FIRST:SEED" >&2; exit 1; }
  poses="$REPO/data/kitti_poses/$trajectory.txt"
  [[ -f "$poses" ]] || { echo "error: no trajectory $poses" >&2; exit 1; }
  results=()
  for h in "${HEIGHT_LIST[@]}"; do
    world="$OUT/world_${trajectory}_${first}_${seed}_${WIDTH}x${HEIGHT}_h$h"
    if [[ ! -f "$world/done" ]]; then
      rm -rf "$world"
      "$DVSO" simulate --trajectory "$poses" --first "$first" --count "$FRAMES" --seed "$seed" --appearance varied \
        --car-detail 0 --width "$WIDTH" --height "$HEIGHT" --color --camera-height "$h" --out "$world" --quiet > "$world.log" 2>&1 ||
        { echo "error: simulate failed, see $world.log" >&2; exit 1; }
      touch "$world/done"
    fi
    pred="$OUT/pred_${tag}_$(basename "$world")"
    rm -rf "$pred"
    "$DVSO" predict --model "$MODEL" --images "$world/image_2" --out "$pred" --no-color > "$pred.log" 2>&1 ||
      { echo "error: predict failed, see $pred.log" >&2; exit 1; }
    "$DVSO" eval-depth --pred "$pred/left" --gt "$world/disp_0" --calib "$world/calib.txt" --max-depth "$MAX_DEPTH" \
      --ranges 0,10,20,40,80 --images "$world/image_2" --min-gradient 100 --json > "$pred.json"
    results+=("$world/simulation.yaml" "$pred.json")
  done
  python3 - "$spec" "${results[@]}" <<'EOF'
import json, math, re, sys
spec, files = sys.argv[1], sys.argv[2:]
rows = []
for yaml_path, json_path in zip(files[::2], files[1::2]):
    height = float(re.search(r"^camera_height:\s*([0-9.eE+-]+)", open(yaml_path).read(), re.M).group(1))
    ranges = json.load(open(json_path))["ranges"]
    far = [r for r in ranges["per_range"] if r["min_depth"] == 40.0]
    rows.append((height, ranges["all"]["median_pred_over_gt"], far[0]["median_pred_over_gt"] if far else float("nan")))
cells = "  ".join(f"h {h:.3f} m: {a:.4f} ({f:.4f})" for h, a, f in rows)
(h0, a0, f0), (h1, a1, f1) = rows[0], rows[-1]
elasticity = lambda r0, r1: math.log(r1 / r0) / math.log(h1 / h0)
print(f"world {spec}: median pred/GT at textured pixels, all (40-80 m): {cells}")
print(f"  elasticity to the camera height: all {elasticity(a0, a1):+.2f}, 40-80 m {elasticity(f0, f1):+.2f}")
EOF
done

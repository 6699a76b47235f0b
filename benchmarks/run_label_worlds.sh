#!/usr/bin/env bash
# Label accuracy on worlds the label filters were not tuned on (issue 12): renders
# KITTI-size (1241x376) simulated stereo segments in every appearance style of the
# simulator (the fixed look and varied looks drawn from seeds never used while
# developing the labels), runs `dvso labels` on each and `dvso eval-labels` (by place:
# thin structures, depth edges, far, low texture, other), then prints one table:
# labels/frame, share within 1 px, within 3 %, MAE, and where the > 1 px labels sit.
#
#   benchmarks/run_label_worlds.sh            (env: DVSO, OUT, COUNT=150 frames per world,
#                                              WORLDS="style:posefile:first:seed[:simulate args] ...", LABEL_ARGS,
#                                              WORLD_VERSION = the binary's simulator world version)
# Optional simulate arguments are comma-separated, e.g. varied:08:1500:9633:--no-edge-aa or
# varied:00:1000:9631:--noise-sigma,3.5 (looks beyond the appearance styles: aliased silhouettes, sensor noise).
# Also writes $OUT/label_worlds.json and $OUT/label_worlds.md (the table, markdown).
set -euo pipefail
REPO=$(cd "$(dirname "$0")/.." && pwd)
DVSO="${DVSO:-$REPO/build/dvso}"
OUT="${OUT:-/tmp/dvso_label_worlds}"
COUNT="${COUNT:-150}"
# Held-out trajectories (08-10) and training ones (00, 05) with seeds 96xx: never used
# for tuning the label filters (those were chosen on seeds 0-9 and 101-114).
WORLDS="${WORLDS:-fixed:08:1000:9601 varied:08:2000:9602 varied:09:300:9603 varied:10:300:9604 varied:00:2000:9605 varied:05:500:9606}"
read -r -a LABEL_EXTRA <<< "${LABEL_ARGS:-}"
[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
# shellcheck source=../scripts/world_version.sh
source "$REPO/scripts/world_version.sh"
WORLD_VERSION="${WORLD_VERSION:-$(binary_world_version "$DVSO")}"
mkdir -p "$OUT"

for world in $WORLDS; do
  IFS=: read -r style poses first seed sim_args <<< "$world"
  IFS=, read -r -a SIM_EXTRA <<< "${sim_args:-}"
  # Another look of the same world gets its own folder (the arguments, made file-name safe).
  suffix="${sim_args//[^A-Za-z0-9.]/}"
  name="${style}_${poses}_${seed}${suffix:+_$suffix}"
  seq="$OUT/$name"
  # A world cached by an earlier run is reused only when it is the simulator world version (core/simulator.h)
  # this run renders; else it is rendered again (its labels would measure another world).
  if [[ -f "$seq/simulation.yaml" && $(recorded_world_version "$seq/simulation.yaml") != "$WORLD_VERSION" ]]; then
    echo "[$(date -u +%H:%M:%S)] $name: cached world is not world version $WORLD_VERSION, rendering it again"
    rm -rf "$seq"
  fi
  if [[ ! -f "$seq/simulation.yaml" ]]; then
    echo "[$(date -u +%H:%M:%S)] simulate $name ($COUNT frames, world version $WORLD_VERSION)"
    "$DVSO" simulate --out "$seq" --trajectory "$REPO/data/kitti_poses/$poses.txt" --first "$first" --count "$COUNT" \
      --seed "$seed" --appearance "$style" --world-version "$WORLD_VERSION" --quiet "${SIM_EXTRA[@]}" \
      > "$OUT/$name.simulate.log"
  fi
  echo "[$(date -u +%H:%M:%S)] labels $name"
  /usr/bin/env time -f "%e" -o "$OUT/$name.labels.seconds" \
    "$DVSO" labels --sequence "$seq" --out "$OUT/$name.labels" --gt-disparity "$seq/disp_0" --overwrite --quiet \
    "${LABEL_EXTRA[@]}" > "$OUT/$name.labels.log"
  "$DVSO" eval-labels --labels "$OUT/$name.labels" --gt "$seq/disp_0" --images "$seq/image_0" --json \
    > "$OUT/$name.eval.json"
done

python3 - "$OUT" $WORLDS <<'EOF'
import json, re, sys
out, worlds = sys.argv[1], sys.argv[2:]
kinds = ["thin", "depth_edge", "far", "low_texture", "other"]
rows, result = [], {}
for w in worlds:
    style, poses, first, seed = w.split(":")[:4]
    sim_args = w.split(":", 4)[4] if w.count(":") > 3 else ""
    look = " ".join([style] + (sim_args.split(",") if sim_args else []))
    suffix = re.sub(r"[^A-Za-z0-9.]", "", sim_args)
    name = f"{style}_{poses}_{seed}" + (f"_{suffix}" if suffix else "")
    j = json.load(open(f"{out}/{name}.eval.json"))
    secs = float(open(f"{out}/{name}.labels.seconds").read().split()[-1])
    result[name] = dict(j, labels_seconds=secs)
    wrong = " / ".join("%.0f" % (100 * j["by_kind"][k]["share_of_wrong"]) for k in kinds)
    within = " / ".join("%.1f" % (100 * j["by_kind"][k]["share_within_threshold"]) for k in kinds)
    rows.append(f"| {look} | KITTI {poses} from {first} | {seed} | {j['frames']} | {j['labels_per_frame_mean']:.0f} "
                f"({j['labels_per_frame_min']}) | {100 * j['share_within_1px']:.2f} | {100 * j['share_within_3_percent']:.2f} "
                f"| {j['mean_abs_error_px']:.3f} | {wrong} | {within} |")
head = ("| look | path | seed | frames | labels/frame mean (min) | within 1 px % | within 3 % % | MAE px "
        "| wrong labels by place % (thin / edge / far / low tex / other) | within 1 px by place % |\n"
        "|---|---|---|---|---|---|---|---|---|---|")
table = head + "\n" + "\n".join(rows)
open(f"{out}/label_worlds.md", "w").write(table + "\n")
json.dump(result, open(f"{out}/label_worlds.json", "w"), indent=2)
print(table)
EOF

#!/usr/bin/env bash
# Accuracy of `dvso odometry` (stereo and mono) on KITTI-layout segments with
# ground truth (e.g. made by `dvso simulate --trajectory data/kitti_poses/05.txt
# --first 100 --count 500 --out /tmp/seg05`), as the table of issue 3:
# stereo t_rel / r_rel without alignment, mono Sim3-aligned ATE RMSE (and as %
# of the path length), lost frames, re-initialisations, keyframes, mean ms/frame
# (wall, from the run log; load-dependent) and CPU ms/frame (user+sys of the
# whole run incl. image decoding: robust to other load on a shared machine).
#
#   benchmarks/run_vo_segments.sh SEGMENT_DIR... [-- extra dvso odometry options]
#   env: DVSO=path/to/dvso (default build/dvso), OUT=work dir (default /tmp/dvso_vo_segments),
#        MODES="stereo mono" (default both)
set -euo pipefail

REPO=$(cd "$(dirname "$0")/.." && pwd)
DVSO="${DVSO:-$REPO/build/dvso}"
OUT="${OUT:-/tmp/dvso_vo_segments}"
MODES="${MODES:-stereo mono}"
SEGMENTS=()
while [[ $# -gt 0 && "$1" != "--" ]]; do SEGMENTS+=("$1"); shift; done
[[ $# -gt 0 ]] && shift
EXTRA=("$@")
if [[ ${#SEGMENTS[@]} -eq 0 ]]; then
  sed -n '2,13p' "$0"
  exit 2
fi
[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "error: python3 is needed to read the JSON metrics" >&2; exit 1; }
mkdir -p "$OUT"

printf "%-10s %-6s %6s %5s %6s %5s %9s %9s %10s %9s %8s %8s\n" segment mode frames lost reinit kf t_rel% r_rel "ATE_m" "ATE%path" "ms/fr" "cpu_ms"
for seg in "${SEGMENTS[@]}"; do
  [[ -f "$seg/poses.txt" ]] || { echo "error: $seg/poses.txt missing" >&2; exit 1; }
  name=$(basename "$seg")
  for mode in $MODES; do
    run="$OUT/${name}_$mode"
    /usr/bin/env time -f "%U %S" -o "$run.time" "$DVSO" odometry --sequence "$seg" --mode "$mode" --out "$run" \
      --no-progress "${EXTRA[@]}" >"$run.log" 2>&1 || { echo "error: odometry failed, see $run.log" >&2; exit 1; }
    align=none
    [[ $mode == mono ]] && align=sim3
    "$DVSO" eval-odometry --gt "$seg/poses.txt" --est "$run/trajectory.txt" --align "$align" --json >"$run.json"
    summary=$(grep -E '^frames ' "$run.log")
    frames=$(sed -E 's/^frames ([0-9]+).*/\1/' <<<"$summary")
    kf=$(sed -E 's/.*keyframes ([0-9]+).*/\1/' <<<"$summary")
    lost=$(sed -E 's/.*lost ([0-9]+).*/\1/' <<<"$summary")
    reinit=$(sed -E 's/.*re-initialisations ([0-9]+).*/\1/' <<<"$summary")
    ms=$(grep -E '^mean ' "$run.log" | sed -E 's/^mean ([0-9.]+).*/\1/')
    cpu=$(awk -v n="$frames" '{printf "%.1f", 1000 * ($1 + $2) / n}' "$run.time")
    python3 - "$run.json" "$name" "$mode" "$frames" "$lost" "$reinit" "$kf" "$ms" "$cpu" <<'EOF'
import json, sys
j = json.load(open(sys.argv[1]))
name, mode, frames, lost, reinit, kf, ms, cpu = sys.argv[2:]
fmt = lambda v, f: (f % v) if isinstance(v, (int, float)) else "n/a"
rmse, path = j.get("ate_rmse"), j.get("gt_path_length")
pct = 100.0 * rmse / path if isinstance(rmse, (int, float)) and path else None
print("%-10s %-6s %6s %5s %6s %5s %9s %9s %10s %9s %8.1f %8s" % (name, mode, frames, lost, reinit, kf,
      fmt(j.get("t_rel"), "%.3f"), fmt(j.get("r_rel"), "%.3f"), fmt(rmse, "%.3f"), fmt(pct, "%.3f"), float(ms), cpu))
EOF
  done
done
echo "outputs and logs: $OUT (stereo metrics unaligned, mono after Sim3 alignment)"

#!/usr/bin/env bash
# The same simulated drive read three ways (issue 11): the KITTI odometry layout,
# a KITTI raw _sync drive (rectified) and a raw _extract drive (distorted,
# unrectified, the right cameras dropping every DROP-th frame; rectified and
# paired by timestamp on read). Odometry in every mode on each; prints the KITTI
# metrics side by side (unaligned except mono, which is Sim(3)-aligned). The raw
# layouts should match the odometry layout: sync exactly (same pixels), extract
# within the loss of two interpolations and the dropped frames.
#
#   benchmarks/run_raw_layouts.sh
#   env: DVSO=path/to/dvso (default build/dvso), OUT=work dir (default /tmp/dvso_raw_layouts),
#        COUNT=frames (default 800), WIDTH/HEIGHT (default 621x188), TRAJECTORY (default KITTI 05),
#        MODES="stereo mono dvso-oracle", DROP=right-camera drop period of the extract drive (default 25)
set -euo pipefail

REPO=$(cd "$(dirname "$0")/.." && pwd)
DVSO="${DVSO:-$REPO/build/dvso}"
OUT="${OUT:-/tmp/dvso_raw_layouts}"
COUNT="${COUNT:-800}"
WIDTH="${WIDTH:-621}"
HEIGHT="${HEIGHT:-188}"
TRAJECTORY="${TRAJECTORY:-$REPO/data/kitti_poses/05.txt}"
MODES="${MODES:-stereo mono dvso-oracle}"
DROP="${DROP:-25}"

[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "error: python3 is needed to read the JSON metrics" >&2; exit 1; }
mkdir -p "$OUT"
sim_args=(--quiet --trajectory "$TRAJECTORY" --count "$COUNT" --width "$WIDTH" --height "$HEIGHT" --appearance varied
          --seed 5151)
if [[ ! -d "$OUT/sync/seq/kitti_raw" ]]; then
  echo "simulating $COUNT frames ${WIDTH}x$HEIGHT (sync drive) ..."
  "$DVSO" simulate "${sim_args[@]}" --out "$OUT/sync/seq" --raw-layout sync >"$OUT/sync.log" 2>&1 ||
    { echo "error: simulation failed, see $OUT/sync.log" >&2; exit 1; }
fi
if [[ ! -d "$OUT/extract/seq/kitti_raw" ]]; then
  echo "simulating $COUNT frames ${WIDTH}x$HEIGHT (extract drive, right cameras drop every $DROP-th frame) ..."
  "$DVSO" simulate "${sim_args[@]}" --out "$OUT/extract/seq" --raw-layout extract --raw-drop-every "$DROP" \
    >"$OUT/extract.log" 2>&1 || { echo "error: simulation failed, see $OUT/extract.log" >&2; exit 1; }
fi
seq="$OUT/sync/seq"
sync_drive="$OUT/sync/seq/kitti_raw/2011_09_26/2011_09_26_drive_0001_sync"
extract_drive="$OUT/extract/seq/kitti_raw/2011_09_26/2011_09_26_drive_0001_extract"

# The raw drives name frames %010d: the oracle's disparity maps (and the GT poses of the frames a drive keeps)
# follow its frame names.
python3 - "$seq" "$OUT" <<'PY'
import os, shutil, sys
seq, out = sys.argv[1:3]
for sub in ("disp_0", "disp_1"):
    dst = os.path.join(out, "raw_" + sub)
    os.makedirs(dst, exist_ok=True)
    for name in sorted(os.listdir(os.path.join(seq, sub))):
        target = os.path.join(dst, "%010d.png" % int(name[:-4]))
        if not os.path.exists(target):
            shutil.copyfile(os.path.join(seq, sub, name), target)
PY

printf "%-10s %-12s %6s %5s %8s %8s %8s\n" layout mode frames lost t_rel% r_rel sim3_s
for layout in odometry sync extract; do
  case $layout in
    odometry) source_dir="$seq"; gt="$seq/poses.txt"; disp_l="$seq/disp_0"; disp_r="$seq/disp_1" ;;
    sync) source_dir="$sync_drive"; gt="$seq/poses.txt"; disp_l="$OUT/raw_disp_0"; disp_r="$OUT/raw_disp_1" ;;
    extract) source_dir="$extract_drive"; disp_l="$OUT/raw_disp_0"; disp_r="$OUT/raw_disp_1"
             # GT of the frames the extract drive keeps (the left camera's file numbers = simulation frames).
             gt="$OUT/extract_gt.txt"
             "$DVSO" oxts-poses --sequence "$extract_drive" --out "$gt" >/dev/null 2>&1 ||
               { echo "error: oxts-poses failed on $extract_drive" >&2; exit 1; } ;;
  esac
  for mode in $MODES; do
    run="$OUT/run_${layout}_$mode"
    case $mode in
      stereo|mono) args=(--mode "$mode") ;;
      dvso-oracle) args=(--mode dvso --disparity-left "$disp_l" --disparity-right "$disp_r") ;;
      *) echo "error: unknown mode $mode" >&2; exit 1 ;;
    esac
    "$DVSO" odometry --sequence "$source_dir" --out "$run" --no-progress "${args[@]}" >"$run.log" 2>&1 ||
      { echo "error: odometry failed, see $run.log" >&2; exit 1; }
    align=none
    [[ $mode == mono ]] && align=sim3
    "$DVSO" eval-odometry --gt "$gt" --est "$run/trajectory.txt" --align "$align" --json >"$run.eval.json"
    "$DVSO" eval-odometry --gt "$gt" --est "$run/trajectory.txt" --align sim3 --json >"$run.sim3.json"
    python3 - "$run" "$layout" "$mode" <<'PY'
import csv, json, sys
run, layout, mode = sys.argv[1:4]
e = json.load(open(run + ".eval.json")); s = json.load(open(run + ".sim3.json"))
rows = list(csv.DictReader(open(run + "/run_log.csv")))
lost = sum(r["status"] == "lost" for r in rows)
fmt = lambda v: f"{v:8.3f}" if v is not None else "       -"
print(f"{layout:<10} {mode:<12} {len(rows):6d} {lost:5d} {fmt(e['t_rel'])} {fmt(e['r_rel'])} {s['scale']:8.4f}")
PY
  done
done

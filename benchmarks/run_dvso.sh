#!/usr/bin/env bash
# DVSO mode measured against mono on the same frames of KITTI-layout
# sequences with ground truth (e.g. `dvso simulate --trajectory
# data/kitti_poses/08.txt --first 100 --count 1500 --appearance varied --seed 8801
# --out /tmp/eval08`). Per sequence and variant, in ONE run so the ratios share
# the machine's load:
#   mono                     DSO, Sim(3)-aligned (scale is arbitrary)
#   stereo                   Stereo DSO (the reference accuracy)
#   dvso-oracle              predictions = the simulator's exact disparities (disp_0/ disp_1/)
#   dvso-model               the shipped model (or $MODEL) run online, keyframe-async (default timing)
#   dvso-model-blocking      the same, each keyframe waits for its prediction
#   dvso-model-speculative   the same, every frame predicted while it is tracked
# Columns: t_rel % and r_rel deg/100 m (KITTI protocol; unaligned except mono), Sim(3)
# scale, lost frames, wall ms/frame of the whole loop (incl. image reading and
# waiting for the network), its ratio to mono, CPU ms/frame (user+sys) and max RSS.
#
#   benchmarks/run_dvso.sh SEQUENCE_DIR... [-- extra dvso odometry options]
#   env: DVSO=path/to/dvso (default build/dvso), OUT=work dir (default /tmp/dvso_bench),
#        MODEL=model.pt (default: the shipped one), VARIANTS="mono stereo dvso-oracle dvso-model ..."
set -euo pipefail

REPO=$(cd "$(dirname "$0")/.." && pwd)
DVSO="${DVSO:-$REPO/build/dvso}"
OUT="${OUT:-/tmp/dvso_bench}"
VARIANTS="${VARIANTS:-mono stereo dvso-oracle dvso-model dvso-model-blocking dvso-model-speculative}"
SEQS=()
while [[ $# -gt 0 && "$1" != "--" ]]; do SEQS+=("$1"); shift; done
[[ $# -gt 0 ]] && shift
EXTRA=("$@")
if [[ ${#SEQS[@]} -eq 0 ]]; then
  sed -n '2,19p' "$0"
  exit 2
fi
[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "error: python3 is needed to read the JSON metrics" >&2; exit 1; }
MODEL_ARGS=()
[[ -n "${MODEL:-}" ]] && MODEL_ARGS=(--model "$MODEL")
mkdir -p "$OUT"

printf "%-10s %-20s %6s %5s %8s %8s %8s %9s %8s %8s %8s\n" sequence variant frames lost t_rel% r_rel sim3_s wall_ms ratio cpu_ms rss_MB
for seq in "${SEQS[@]}"; do
  [[ -f "$seq/poses.txt" ]] || { echo "error: $seq/poses.txt missing" >&2; exit 1; }
  name=$(basename "$seq")
  mono_wall=""
  for variant in $VARIANTS; do
    run="$OUT/${name}_$variant"
    case $variant in
      mono) args=(--mode mono) ;;
      stereo) args=(--mode stereo) ;;
      dvso-oracle) args=(--mode dvso --disparity-left "$seq/disp_0" --disparity-right "$seq/disp_1") ;;
      dvso-model) args=(--mode dvso "${MODEL_ARGS[@]}" --prediction-schedule keyframe-async) ;;
      dvso-model-blocking) args=(--mode dvso "${MODEL_ARGS[@]}" --prediction-schedule keyframe-blocking) ;;
      dvso-model-speculative) args=(--mode dvso "${MODEL_ARGS[@]}" --prediction-schedule speculative) ;;
      *) echo "error: unknown variant $variant" >&2; exit 1 ;;
    esac
    /usr/bin/env time -f "%U %S %M" -o "$run.time" "$DVSO" odometry --sequence "$seq" --out "$run" --no-progress \
      "${args[@]}" "${EXTRA[@]}" >"$run.log" 2>&1 || { echo "error: odometry failed, see $run.log" >&2; exit 1; }
    align=none
    [[ $variant == mono ]] && align=sim3
    "$DVSO" eval-odometry --gt "$seq/poses.txt" --est "$run/trajectory.txt" --align "$align" --json >"$run.eval.json"
    "$DVSO" eval-odometry --gt "$seq/poses.txt" --est "$run/trajectory.txt" --align sim3 --json >"$run.sim3.json"
    read -r frames lost wall <<<"$(python3 - "$run/run_log.csv" "$run.log" <<'PY'
import csv, re, sys
rows = list(csv.DictReader(open(sys.argv[1])))
text = open(sys.argv[2]).read()
wall = re.search(r"wall ([0-9.]+) ms/frame", text).group(1)
print(len(rows), sum(r["status"] == "lost" for r in rows), wall)
PY
)"
    [[ $variant == mono ]] && mono_wall=$wall
    python3 - "$run.eval.json" "$run.sim3.json" "$run.time" "$name" "$variant" "$frames" "$lost" "$wall" "${mono_wall:-0}" <<'PY'
import json, sys
e = json.load(open(sys.argv[1])); s = json.load(open(sys.argv[2]))
user, system, rss_kb = open(sys.argv[3]).read().split()[-3:]
name, variant, frames, lost, wall, mono_wall = sys.argv[4:10]
frames = int(frames); wall = float(wall); mono_wall = float(mono_wall)
ratio = f"{wall / mono_wall:.2f}" if mono_wall > 0 else "-"
cpu = (float(user) + float(system)) * 1000 / max(frames, 1)
fmt = lambda v, spec: format(v, spec) if v is not None else format("-", ">" + spec.split(".")[0])
print(f"{name:<10} {variant:<20} {frames:6d} {int(lost):5d} {fmt(e['t_rel'], '8.3f')} {fmt(e['r_rel'], '8.3f')} {s['scale']:8.4f} "
      f"{wall:9.1f} {ratio:>8} {cpu:8.1f} {int(rss_kb)/1024:8.0f}")
PY
  done
done
echo "(wall_ms: whole loop per frame incl. image reading and prediction; ratio = wall_ms / mono's wall_ms on the same frames)"

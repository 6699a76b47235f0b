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
#        MODEL=model.pt (default: the shipped one), VARIANTS="mono stereo dvso-oracle dvso-model ...",
#        REPEAT=n (default 1): n interleaved repetitions, medians printed (the 2-core
#        machines' wall times vary by 10-20 % between identical runs)
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
  sed -n '2,21p' "$0"
  exit 2
fi
[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "error: python3 is needed to read the JSON metrics" >&2; exit 1; }
MODEL_ARGS=()
[[ -n "${MODEL:-}" ]] && MODEL_ARGS=(--model "$MODEL")
mkdir -p "$OUT"

REPEAT="${REPEAT:-1}"
[[ "$REPEAT" =~ ^[1-9][0-9]*$ ]] || { echo "error: REPEAT must be a positive integer" >&2; exit 1; }

printf "%-10s %-20s %6s %5s %8s %8s %8s %9s %8s %8s %8s\n" sequence variant frames lost t_rel% r_rel sim3_s wall_ms ratio cpu_ms rss_MB
for seq in "${SEQS[@]}"; do
  [[ -f "$seq/poses.txt" ]] || { echo "error: $seq/poses.txt missing" >&2; exit 1; }
  name=$(basename "$seq")
  runs=()
  # Repetitions are interleaved (mono, dvso, ..., mono, dvso, ...) so that a slow
  # spell of the machine hits every variant alike.
  for ((rep = 1; rep <= REPEAT; rep++)); do
    for variant in $VARIANTS; do
      run="$OUT/${name}_$variant"
      [[ $REPEAT -gt 1 ]] && run+="_r$rep"
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
      runs+=("$variant=$run")
    done
  done
  # One line per variant: medians over the repetitions (t_rel and scale of every
  # repetition in the JSON next to the runs when REPEAT > 1).
  python3 - "$name" "$OUT/${name}_summary.json" "${runs[@]}" <<'PY'
import csv, json, re, statistics, sys
name, summary_path, items = sys.argv[1], sys.argv[2], sys.argv[3:]
by_variant = {}
for item in items:
    variant, run = item.split("=", 1)
    rows = list(csv.DictReader(open(run + "/run_log.csv")))
    wall = float(re.search(r"wall ([0-9.]+) ms/frame", open(run + ".log").read()).group(1))
    user, system, rss_kb = open(run + ".time").read().split()[-3:]
    e = json.load(open(run + ".eval.json")); s = json.load(open(run + ".sim3.json"))
    by_variant.setdefault(variant, []).append({
        "run": run, "frames": len(rows), "lost": sum(r["status"] == "lost" for r in rows), "wall_ms": wall,
        "cpu_ms": (float(user) + float(system)) * 1000 / max(len(rows), 1), "rss_mb": int(rss_kb) / 1024,
        "t_rel": e["t_rel"], "r_rel": e["r_rel"], "scale": s["scale"]})
med = lambda runs, key: statistics.median(r[key] for r in runs if r[key] is not None) \
    if any(r[key] is not None for r in runs) else None
mono_wall = med(by_variant["mono"], "wall_ms") if "mono" in by_variant else None
fmt = lambda v, spec: format(v, spec) if v is not None else format("-", ">" + spec.split(".")[0])
summary = {}
for variant, runs in by_variant.items():
    wall = med(runs, "wall_ms")
    ratio = wall / mono_wall if mono_wall else None
    summary[variant] = {"runs": runs, "median_wall_ms": wall, "ratio_to_mono": ratio}
    print(f"{name:<10} {variant:<20} {runs[0]['frames']:6d} {max(r['lost'] for r in runs):5d} "
          f"{fmt(med(runs, 't_rel'), '8.3f')} {fmt(med(runs, 'r_rel'), '8.3f')} {med(runs, 'scale'):8.4f} "
          f"{wall:9.1f} {fmt(ratio, '8.2f')} {med(runs, 'cpu_ms'):8.1f} {max(r['rss_mb'] for r in runs):8.0f}")
json.dump(summary, open(summary_path, "w"), indent=1)
PY
done
if [[ $REPEAT -gt 1 ]]; then
  echo "(medians of $REPEAT interleaved repetitions; lost and rss_MB: the maximum; every run in \$OUT/<sequence>_summary.json)"
fi
echo "(wall_ms: whole loop per frame incl. image reading and prediction; ratio = wall_ms / mono's wall_ms on the same frames)"

#!/usr/bin/env bash
# Soak run (issue 11): odometry over a KITTI-00-length simulated sequence (4541
# frames along the real KITTI 00 path) in stereo and mono mode. Prints the
# resident set size sampled every 100 frames from run_log.csv (the curve), its
# growth between the first and last quarter of the run, frames lost and the
# KITTI metrics; writes the curve to $OUT/soak_rss.csv.
#
#   benchmarks/run_soak.sh
#   env: DVSO=path/to/dvso (default build/dvso), OUT=work dir (default /tmp/dvso_soak),
#        COUNT=frames (default 4541), WIDTH/HEIGHT (default 1241x376), MODES="stereo mono",
#        SEED=world seed (default 4541)
set -euo pipefail

REPO=$(cd "$(dirname "$0")/.." && pwd)
DVSO="${DVSO:-$REPO/build/dvso}"
OUT="${OUT:-/tmp/dvso_soak}"
COUNT="${COUNT:-4541}"
WIDTH="${WIDTH:-1241}"
HEIGHT="${HEIGHT:-376}"
MODES="${MODES:-stereo mono}"
SEED="${SEED:-4541}"
SAMPLE_EVERY=100

[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "error: python3 is needed to read run_log.csv" >&2; exit 1; }
mkdir -p "$OUT"
seq_dir="$OUT/seq_${COUNT}_${WIDTH}x${HEIGHT}_$SEED"
if [[ ! -f "$seq_dir/poses.txt" ]] || [[ $(wc -l <"$seq_dir/poses.txt") -ne $COUNT ]]; then
  echo "simulating $COUNT frames ${WIDTH}x$HEIGHT along KITTI 00 into $seq_dir"
  "$DVSO" simulate --quiet --out "$seq_dir" --trajectory "$REPO/data/kitti_poses/00.txt" --count "$COUNT" \
    --width "$WIDTH" --height "$HEIGHT" --seed "$SEED" --appearance varied >"$OUT/simulate.log" 2>&1 ||
    { echo "error: simulation failed, see $OUT/simulate.log" >&2; exit 1; }
fi

logs=()
for mode in $MODES; do
  run="$OUT/$mode"
  echo "odometry --mode $mode over $COUNT frames ..."
  /usr/bin/env time -f "%e %M" -o "$run.time" "$DVSO" odometry --sequence "$seq_dir" --out "$run" --mode "$mode" \
    --no-progress >"$run.log" 2>&1 || { echo "error: odometry failed, see $run.log" >&2; exit 1; }
  align=none
  [[ $mode == mono ]] && align=sim3
  "$DVSO" eval-odometry --gt "$seq_dir/poses.txt" --est "$run/trajectory.txt" --align "$align" --json >"$run.eval.json"
  logs+=("$mode=$run")
done

python3 - "$OUT/soak_rss.csv" "$COUNT" "$SAMPLE_EVERY" "${logs[@]}" <<'PY'
import csv, json, sys
out_csv, count, every = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
runs = [a.split("=", 1) for a in sys.argv[4:]]
curves, summary = {}, []
for mode, run in runs:
    rows = list(csv.DictReader(open(run + "/run_log.csv")))
    rss = {int(r["frame"]): float(r["rss_mb"]) for r in rows}
    curves[mode] = rss
    lost = sum(r["status"] == "lost" for r in rows)
    wall, max_kb = open(run + ".time").read().split()[-2:]
    metrics = json.load(open(run + ".eval.json"))
    frames = sorted(rss)
    quarter = max(len(frames) // 4, 1)
    first_q = sum(rss[f] for f in frames[:quarter]) / quarter
    last_q = sum(rss[f] for f in frames[-quarter:]) / quarter
    traj_lines = sum(1 for _ in open(run + "/trajectory.txt"))
    summary.append((mode, len(rows), traj_lines, lost, first_q, last_q, int(max_kb) / 1024, float(wall),
                    metrics.get("t_rel"), metrics.get("r_rel")))
samples = list(range(0, count, every)) + ([count - 1] if (count - 1) % every else [])
with open(out_csv, "w") as f:
    f.write("frame," + ",".join(f"{m}_rss_mb" for m, _ in runs) + "\n")
    for s in samples:
        f.write(str(s) + "," + ",".join(f"{curves[m].get(s, float('nan')):.1f}" for m, _ in runs) + "\n")
print("\nRSS (MB) every %d frames:" % every)
print("frame " + " ".join(f"{m:>8}" for m, _ in runs))
for s in samples:
    print(f"{s:5d} " + " ".join(f"{curves[m].get(s, float('nan')):8.1f}" for m, _ in runs))
print("\nmode    frames traj_lines lost rss_first_quarter rss_last_quarter growth max_rss_MB wall_s  t_rel%  r_rel")
fmt = lambda v: f"{v:7.3f}" if v is not None else "      -"
for mode, frames, lines, lost, fq, lq, mx, wall, t, r in summary:
    print(f"{mode:<7} {frames:6d} {lines:10d} {lost:4d} {fq:17.1f} {lq:16.1f} {lq / fq:6.3f} {mx:10.1f} {wall:6.0f} "
          f"{fmt(t)} {fmt(r)}")
PY

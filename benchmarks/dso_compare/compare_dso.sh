#!/usr/bin/env bash
# Side-by-side speed (and accuracy) of the original DSO and `dvso odometry --mode mono`
# on the same KITTI-layout sequence (e.g. from `dvso simulate`).
#
#   benchmarks/dso_compare/compare_dso.sh DSO_SOURCE_DIR SEQUENCE_DIR [FRAMES=500] [WORK_DIR=/tmp/dvso_dso_compare]
#
# DSO_SOURCE_DIR: a checkout of https://github.com/JakobEngel/dso that YOU provide (its code is
# GPL and never part of this repository). Its library is built here with its own CMake (needs
# Boost thread/system: installed below), and our headless driver (dso_timing_driver.cpp, which
# replaces DSO's Pangolin-based example main) is linked against it.
#
# Fairness: both systems process every frame fully (DSO with linearizeOperation, i.e. no
# real-time frame skipping), default settings (2000 points, 7 keyframes), no photometric
# calibration file, image loading excluded from the timings. DSO's pyramid needs sizes divisible
# by 8, so DSO gets the top-left (W/8*8)x(H/8*8) of each image through its own undistorter with the
# same intrinsics (1240x376 of KITTI's 1241x376: one column less); dvso runs on the full image. Threads: DSO uses its default
# thread pool, dvso its default num_threads (2); both on the same machine, one after the other.
set -euo pipefail

if [[ $# -lt 2 ]]; then
  sed -n '2,9p' "$0"
  exit 2
fi
DSO_SRC=$(realpath "$1")
SEQ=$(realpath "$2")
FRAMES=${3:-500}
WORK=${4:-/tmp/dvso_dso_compare}
REPO=$(cd "$(dirname "$0")/../.." && pwd)
DVSO="${DVSO:-$REPO/build/dvso}"

[[ -f "$DSO_SRC/src/FullSystem/FullSystem.h" ]] || { echo "error: $DSO_SRC is not a DSO checkout" >&2; exit 1; }
[[ -f "$SEQ/calib.txt" && -d "$SEQ/image_0" ]] || { echo "error: $SEQ is not a KITTI-layout sequence" >&2; exit 1; }
[[ -x "$DVSO" ]] || { echo "error: $DVSO not built (scripts/build.sh, or set DVSO=path/to/dvso)" >&2; exit 1; }
mkdir -p "$WORK"

# 1. DSO's extra dependencies (idempotent).
if ! dpkg -s libboost-thread-dev libboost-system-dev >/dev/null 2>&1; then
  SUDO=""; [[ $(id -u) -ne 0 ]] && SUDO=sudo
  $SUDO apt-get update -qq  # images whose package lists were cleaned would not find them otherwise
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends libboost-thread-dev \
    libboost-system-dev
fi

# 2. DSO library + our driver. DSO (2017) predates two API removals in Debian 12's libraries:
# Boost >= 1.73 no longer puts boost::bind's _1.._4 in the global namespace (the define + header
# restore them) and OpenCV 4 dropped the CV_LOAD_IMAGE_* constants (mapped to cv::IMREAD_* values).
COMPAT_FLAGS="-DBOOST_BIND_GLOBAL_PLACEHOLDERS -include boost/bind.hpp -DCV_LOAD_IMAGE_UNCHANGED=-1 \
-DCV_LOAD_IMAGE_GRAYSCALE=0 -DCV_LOAD_IMAGE_COLOR=1"
if [[ ! -f "$WORK/dso_build/lib/libdso.a" ]]; then
  # DSO overwrites CMAKE_CXX_FLAGS, so the compatibility flags go through the Release flags.
  cmake -S "$DSO_SRC" -B "$WORK/dso_build" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS_RELEASE="-O3 -DNDEBUG $COMPAT_FLAGS" >"$WORK/dso_cmake.log" 2>&1
  make -C "$WORK/dso_build" -j"$(nproc)" dso >"$WORK/dso_make.log" 2>&1 || { echo "error: DSO build failed, see $WORK/dso_make.log" >&2; exit 1; }
fi
if [[ ! -x "$WORK/dso_timing_driver" || "$REPO/benchmarks/dso_compare/dso_timing_driver.cpp" -nt "$WORK/dso_timing_driver" ]]; then
  # shellcheck disable=SC2046
  g++ -O3 -march=native -std=c++14 -DENABLE_SSE $COMPAT_FLAGS -w \
    -I"$DSO_SRC/src" -I"$DSO_SRC/thirdparty/Sophus" -I"$DSO_SRC/thirdparty/sse2neon" \
    -I/usr/include/eigen3 -I/usr/include/suitesparse $(pkg-config --cflags opencv4) \
    "$REPO/benchmarks/dso_compare/dso_timing_driver.cpp" -o "$WORK/dso_timing_driver" \
    "$WORK/dso_build/lib/libdso.a" -lboost_system -lboost_thread -lcxsparse $(pkg-config --libs opencv4) -lpthread
fi

# 3. DSO camera file from KITTI's P0 (pinhole, no distortion), output 1240x368 with the same K.
read -r FX CX FY CY < <(awk '/^P0:/ {print $2, $4, $7, $8}' "$SEQ/calib.txt")
read -r W H < <(python3 -c "import struct,sys
f=open(sys.argv[1],'rb'); f.read(16); print(*struct.unpack('>II', f.read(8)))" "$(ls "$SEQ"/image_0/*.png | head -1)")
OW=$(( W / 8 * 8 )); OH=$(( H / 8 * 8 ))
python3 - "$FX" "$FY" "$CX" "$CY" "$W" "$H" "$OW" "$OH" >"$WORK/camera_dso.txt" <<'EOF'
import sys
fx, fy, cx, cy = map(float, sys.argv[1:5]); w, h, ow, oh = map(int, sys.argv[5:9])
print(f"Pinhole {fx} {fy} {cx} {cy} 0")
print(f"{w} {h}")
# DSO's relative output calibration: K = (fx*ow, fy*oh, cx*ow - 0.5, cy*oh - 0.5).
print(f"{fx/ow:.9f} {fy/oh:.9f} {(cx+0.5)/ow:.9f} {(cy+0.5)/oh:.9f} 0")
print(f"{ow} {oh}")
EOF

# 4. Run both, one after the other.
echo "== DSO (${OW}x${OH}), $FRAMES frames"
"$WORK/dso_timing_driver" "$SEQ/image_0" "$WORK/camera_dso.txt" "$WORK/dso_trajectory_tum.txt" "$FRAMES" \
  >"$WORK/dso_stdout.log" 2>"$WORK/dso_stderr.log"
DSO_LINE=$(grep '^dso frames=' "$WORK/dso_stdout.log")
echo "$DSO_LINE"

echo "== dvso mono (${W}x${H}), $FRAMES frames"
"$DVSO" odometry --sequence "$SEQ" --mode mono --count "$FRAMES" --out "$WORK/dvso_mono" --no-progress >"$WORK/dvso.log" 2>&1
DVSO_LINE=$(python3 - "$WORK/dvso_mono/run_log.csv" <<'EOF'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
ms = [float(r["total_ms"]) for r in rows]
lost = sum(r["status"] == "lost" for r in rows)
print(f"dvso frames={len(ms)} lost={lost} mean_ms={statistics.mean(ms):.2f} median_ms={statistics.median(ms):.2f}")
EOF
)
echo "$DVSO_LINE"

python3 - "$DSO_LINE" "$DVSO_LINE" <<'EOF'
import sys
def field(line, key): return float(dict(kv.split("=") for kv in line.split()[1:])[key])
dso, ours = sys.argv[1], sys.argv[2]
print(f"ratio dvso/dso mean ms per frame: {field(ours,'mean_ms') / field(dso,'mean_ms'):.2f} "
      f"(median {field(ours,'median_ms') / field(dso,'median_ms'):.2f})")
EOF
echo "Trajectories: $WORK/dso_trajectory_tum.txt (DSO, TUM, tracked frames), $WORK/dvso_mono/trajectory.txt"

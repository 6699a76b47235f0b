#!/usr/bin/env bash
# Issue 10 item 6: the label-to-model pipeline on a lent GPU machine, in one command that ends inside the device
# tool's 10-minute limit: unpack the dependency bundle, build `dvso` against the machine's CUDA LibTorch, render and
# label the training worlds on all cores, measure the training speed, train configs/stacknet_gpu.yaml with its
# steps scaled to the time left, export, evaluate on the held-out worlds and put the model and its numbers in $OUT.
#
# Here, once (needs no GPU):   scripts/gpu/make_bundle.sh        -> .gpu_bundle/dvso_bundle.tar.xz
# Then, with the device tool:  run(command="scripts/gpu/train_on_device.sh", carry=[".gpu_bundle"], timeout_s=600)
# Back here:                   scripts/gpu/collect_model.sh DIR   (DIR = the reply's files_at: joins the weights and
#                                                                 exports the model with this machine's LibTorch)
#
#   scripts/gpu/train_on_device.sh [all|prepare|train]    (default all; prepare = build + data, train = the rest:
#                                                          two calls on one warm machine when a build is slow)
# Environment:
#   OUT                         results folder (the device tool sets it; default ./gpu_out)
#   TOTAL_SECONDS=560           wall-clock budget of this command, all steps included
#   EVAL_RESERVE_SECONDS=75     kept for export, evaluation and packing after training
#   BUNDLE=.gpu_bundle/dvso_bundle.tar.xz   from make_bundle.sh (prefix /opt/dvso-bundle inside)
#   BUILD_DIR=build-gpu         JOBS=$(nproc)   PYTHON=python3
#   TORCH_CMAKE                 LibTorch's CMake folder; default: the Python torch's cmake_prefix_path
#   CONFIG=configs/stacknet_gpu.yaml          the run's config; its stage steps are scaled to the time left
#   DATA=/tmp/dvso_stacknet_v4  WORLDS=v4     as scripts/train_stacknet.sh (the config's data paths point there)
#   REQUIRE_CUDA=1              0 = allow a CPU LibTorch (this script's own test on a machine without a GPU)
set -euo pipefail
cd "$(dirname "$0")/../.."
PHASE=${1:-all}
START=$SECONDS
TOTAL_SECONDS=${TOTAL_SECONDS:-560}
EVAL_RESERVE_SECONDS=${EVAL_RESERVE_SECONDS:-75}
OUT=${OUT:-$PWD/gpu_out}
BUNDLE=${BUNDLE:-.gpu_bundle/dvso_bundle.tar.xz}
BUILD_DIR=${BUILD_DIR:-build-gpu}
JOBS=${JOBS:-$(nproc)}
PYTHON=${PYTHON:-python3}
CONFIG=${CONFIG:-configs/stacknet_gpu.yaml}
export DATA=${DATA:-/tmp/dvso_stacknet_v4} WORLDS=${WORLDS:-v4}
REQUIRE_CUDA=${REQUIRE_CUDA:-1}
RUN=$DATA/run_gpu
DVSO=$BUILD_DIR/dvso
mkdir -p "$OUT"
LOG=$OUT/device_log.txt
log() { echo "[$((SECONDS - START)) s] $*" | tee -a "$LOG" >&2; }  # stderr: stdout of some steps is data
fail() { log "error: $*"; exit 1; }
# A step that fails under `set -e` says which one (a device call returns only the output's tail).
trap 'log "error: \"$BASH_COMMAND\" failed (line $LINENO)"' ERR
seconds_left() { echo $((TOTAL_SECONDS - (SECONDS - START))); }

phase_prepare() {
  log "machine: $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GB; $(nvidia-smi --query-gpu=name,memory.total --format=csv,noheader 2>/dev/null || echo 'no nvidia-smi')"
  [[ -f "$BUNDLE" ]] || fail "no $BUNDLE: run scripts/gpu/make_bundle.sh here first and carry .gpu_bundle"
  tar -C / -xJf "$BUNDLE"
  local prefix
  prefix=$(tar -tJf "$BUNDLE" | awk -F/ 'NR == 1 {print "/" $1 "/" $2}')  # awk reads on: no SIGPIPE for tar
  if [[ -z "${TORCH_CMAKE:-}" ]] && "$PYTHON" -c "import torch" 2>/dev/null; then
    TORCH_CMAKE=$("$PYTHON" -c "import torch; print(torch.utils.cmake_prefix_path)")
    log "$("$PYTHON" -c "import torch; print('PyTorch', torch.__version__, 'CUDA', torch.version.cuda, 'available', torch.cuda.is_available())")"
  fi
  # A CUDA build of LibTorch's CMake package looks for the CUDA toolkit; point it at the nvcc on the PATH.
  local cuda_hint=()
  if command -v nvcc > /dev/null; then
    cuda_hint=(-DCUDAToolkit_ROOT="$(dirname "$(dirname "$(command -v nvcc)")")")
  fi
  log "configure against bundle $prefix and LibTorch ${TORCH_CMAKE:-(system)} ${cuda_hint[*]:-}"
  # CMAKE_FIND_PACKAGE_PREFER_CONFIG + the bundle first: its static OpenCV and yaml-cpp, not a system copy.
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DDVSO_WITH_TORCH=ON -DDVSO_BUILD_TESTS=OFF \
    -DDVSO_BUILD_BENCHMARKS=OFF -DCMAKE_PREFIX_PATH="$prefix${TORCH_CMAKE:+;$TORCH_CMAKE}" \
    -DCMAKE_FIND_PACKAGE_PREFER_CONFIG=ON "${cuda_hint[@]}" > "$OUT/cmake.log" 2>&1 || { tail -30 "$OUT/cmake.log"; fail "configure failed"; }
  local build_start=$SECONDS
  cmake --build "$BUILD_DIR" -j "$JOBS" --target dvso stacknet_figures > "$OUT/build.log" 2>&1 ||
    { grep -m 20 -A 5 "error" "$OUT/build.log"; fail "build failed (build.log)"; }
  log "built $DVSO in $((SECONDS - build_start)) s"
  # The bundle's static OpenCV and yaml-cpp must be what was linked (no system copy exists there; here one may).
  # Direct dependencies only: Debian's LibTorch itself loads Debian's OpenCV (`ldd` lists it through libtorch).
  ! readelf -d "$DVSO" | grep NEEDED | grep -E "libopencv|libyaml-cpp" ||
    fail "$DVSO links a shared OpenCV or yaml-cpp, not the bundle's"
  if [[ $REQUIRE_CUDA == 1 ]]; then
    local bench
    bench=$("$DVSO" bench --model models/stacknet_cpu_main.pt --device cuda --runs 20 --json) ||
      fail "dvso cannot run the shipped model on CUDA (see above)"
    log "CUDA LibTorch works; the shipped model: $(echo "$bench" | tr -d '\n ')"
  fi
  local data_start=$SECONDS
  DVSO=$DVSO JOBS=$JOBS NICE=0 scripts/train_stacknet.sh data > "$OUT/data.log" 2>&1 ||
    { tail -20 "$OUT/data.log"; fail "data step failed (data.log)"; }
  log "rendered and labelled $(ls -d "$DATA"/w* | grep -vc '\.log$') training worlds in $((SECONDS - data_start)) s"
}

# Seconds per step of a stage kind ("simple" or "stack"), measured by a short run of the config itself.
measure_step_seconds() {
  local probe=$DATA/probe
  rm -rf "$probe" && mkdir -p "$probe"
  "$PYTHON" scripts/gpu/stage_steps.py probe "$CONFIG" "$probe/config.yaml"
  "$DVSO" train --config "$probe/config.yaml" --output-dir "$probe/run" > "$probe/train.log" 2>&1 ||
    { tail -20 "$probe/train.log" >&2; fail "probe training failed"; }
  "$PYTHON" - "$probe/run/epochs.jsonl" <<'EOF'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
timed = {}
for r in rows:
    if r["epoch"] == 1:  # the second epoch of each probe stage
        timed["simple" if "simple" in r["stage_name"] else "stack"] = r["seconds"] / max(1, r["timed_steps"])
print(timed["simple"], timed["stack"])
EOF
}

phase_train() {
  [[ -x "$DVSO" && -d "$DATA/heldout_all" ]] || fail "run the prepare phase first (no $DVSO or no data in $DATA)"
  local simple_s stack_s
  read -r simple_s stack_s < <(measure_step_seconds)
  [[ -n "${stack_s:-}" ]] || fail "the probe training gave no step times ($DATA/probe/train.log)"
  local budget=$(( $(seconds_left) - EVAL_RESERVE_SECONDS ))
  (( budget > 30 )) || fail "only $budget s left for training"
  log "step time: SimpleNet $simple_s s, StackNet $stack_s s; $budget s for training"
  # A fresh run folder: the export and evaluation steps of train_stacknet.sh keep what an earlier run left there.
  rm -rf "$RUN" && mkdir -p "$RUN"
  local scaled
  scaled=$("$PYTHON" scripts/gpu/stage_steps.py scale "$CONFIG" "$RUN/config_scaled.yaml" "$simple_s" "$stack_s" "$budget")
  log "$scaled ($RUN/config_scaled.yaml)"
  # The learning curve (held-out abs rel after every epoch) beside the training, as the CPU pipeline does.
  rm -f "$RUN/train.done" "$RUN/curve.csv"
  DVSO=$DVSO RUN=$RUN NICE=0 scripts/train_stacknet.sh monitor > "$RUN/curve_monitor.log" 2>&1 &
  local monitor=$! train_start=$SECONDS
  "$DVSO" train --config "$RUN/config_scaled.yaml" --output-dir "$RUN" > "$RUN/train.log" 2>&1 ||
    { kill "$monitor" 2>/dev/null; tail -20 "$RUN/train.log"; fail "training failed"; }
  touch "$RUN/train.done"
  # The monitor evaluates the last epochs' checkpoints; it may not hold up the rest.
  timeout 30 tail --pid="$monitor" -f /dev/null || kill "$monitor" 2>/dev/null || true
  log "trained in $((SECONDS - train_start)) s"
  DVSO=$DVSO CONFIG=$RUN/config_scaled.yaml RUN=$RUN FINETUNE_CONFIG="" DOCS=$RUN/docs NICE=0 \
    scripts/train_stacknet.sh export > "$OUT/export.log" 2>&1 || fail "export failed"
  DVSO=$DVSO CONFIG=$RUN/config_scaled.yaml RUN=$RUN FINETUNE_CONFIG="" DOCS=$RUN/docs NICE=0 \
    scripts/train_stacknet.sh eval > "$OUT/eval.log" 2>&1 || { tail -20 "$OUT/eval.log"; fail "evaluation failed"; }
  if [[ $REQUIRE_CUDA == 1 ]]; then
    log "GPU latency of the new StackNet: $("$DVSO" bench --model "$RUN/stacknet.pt" --device cuda --dtype all --runs 50 --json | tr -d '\n ')"
  fi
  log "held-out StackNet: $("$PYTHON" -c "import json; m=json.load(open('$RUN/docs/stacknet_metrics.json'))['stacknet']['all']; print('abs rel %.4f d1 %.3f' % (m['abs_rel'], m['a1']))")"
  # At most 8 files of <= 16 MiB come back. The model travels as a weights-only checkpoint in 15 MiB parts, not as
  # this machine's TorchScript file: `dvso export` here, with Debian's LibTorch 1.13, makes the file that every
  # other machine loads (a TorchScript file written by a newer LibTorch need not load in an older one), with the
  # training camera this machine recorded in its export (model_metadata.json).
  "$DVSO" export --checkpoint "$RUN/checkpoint_final.pt" --weights-only --out "$RUN/weights_final.pt" > /dev/null
  split -b 15M -d "$RUN/weights_final.pt" "$OUT/weights_final.pt.part"
  sha256sum "$RUN/weights_final.pt" | cut -d' ' -f1 > "$OUT/weights_final.pt.sha256"
  "$PYTHON" - "$RUN/stacknet.pt" "$OUT/model_metadata.json" <<'EOF'
import sys, zipfile
with zipfile.ZipFile(sys.argv[1]) as z:  # a TorchScript file is a zip; extra files sit under <name>/extra/
    name = next(n for n in z.namelist() if n.endswith("/extra/dvso_metadata.json"))
    open(sys.argv[2], "wb").write(z.read(name))
EOF
  cp "$RUN/docs/stacknet_metrics.json" "$OUT/"
  tar -C "$RUN" -czf "$OUT/run_logs.tgz" config_scaled.yaml epochs.jsonl train.log docs \
    $(cd "$RUN" && ls losses.csv curve.csv 2>/dev/null)
  rm -f "$OUT/cmake.log" "$OUT/build.log" "$OUT/data.log" "$OUT/export.log" "$OUT/eval.log"  # 8 files at most
  log "done in $((SECONDS - START)) s: $(ls "$OUT" | tr '\n' ' ')"
}

case "$PHASE" in
  all) phase_prepare; phase_train ;;
  prepare) phase_prepare ;;
  train) phase_train ;;
  *) echo "usage: $0 [all|prepare|train]" >&2; exit 2 ;;
esac

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
set -Eeuo pipefail  # -E: the ERR trap below also fires inside functions
cd "$(dirname "$0")/../.."
PHASE=${1:-all}
START=$SECONDS
TOTAL_SECONDS_GIVEN=${TOTAL_SECONDS:-}
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
# The device tool stops a command at 600 s; the evaluation may run until TOTAL_SECONDS + 25 s, plus 5 s to be killed.
(( TOTAL_SECONDS <= 560 )) || { echo "error: TOTAL_SECONDS must be <= 560 (the device tool's 600 s limit)" >&2; exit 1; }
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
  local gpu
  gpu=$(nvidia-smi --query-gpu=name,memory.total --format=csv,noheader 2>/dev/null || echo 'no nvidia-smi')
  log "machine: $(nproc) cores, $(free -g | awk '/Mem:/ {print $2}') GB; $gpu"
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
    -DCMAKE_FIND_PACKAGE_PREFER_CONFIG=ON "${cuda_hint[@]}" > "$OUT/cmake.log" 2>&1 ||
    { tail -30 "$OUT/cmake.log"; fail "configure failed"; }
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
  # Kept only when a step failed: $OUT may hold 8 files, and the train phase needs 6.
  rm -f "$OUT/cmake.log" "$OUT/build.log" "$OUT/data.log"
}

# Prints "SIMPLE_S STACK_S EPOCH_OVERHEAD_S": seconds per SimpleNet and StackNet step, measured by a short run of the
# config itself (the second epoch of each probe stage; the first includes start-up), and the seconds per epoch
# outside its timed steps (checkpoint writing, loader start): the wall time between the records of a stage's two
# epochs, which appear in epochs.jsonl as they end, minus the second epoch's timed seconds.
measure_step_seconds() {
  local probe=$DATA/probe
  rm -rf "$probe" && mkdir -p "$probe/run"
  "$PYTHON" scripts/gpu/stage_steps.py probe "$CONFIG" "$probe/config.yaml"
  "$DVSO" train --config "$probe/config.yaml" --output-dir "$probe/run" > "$probe/train.log" 2>&1 &
  local pid=$! seen=0 lines times=()
  while kill -0 "$pid" 2> /dev/null; do
    lines=0
    if [[ -f "$probe/run/epochs.jsonl" ]]; then lines=$(wc -l < "$probe/run/epochs.jsonl"); fi
    while (( seen < lines )); do times+=("$EPOCHREALTIME"); seen=$((seen + 1)); done
    sleep 0.05
  done
  wait "$pid" || { tail -20 "$probe/train.log" >&2; fail "probe training failed"; }
  "$PYTHON" - "$probe/run/epochs.jsonl" "${times[@]}" <<'EOF'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
seen = [float(t) for t in sys.argv[2:]]  # when each record appeared, for the records seen while the run was on
timed, overheads = {}, []
for i, r in enumerate(rows):
    if r["epoch"] == 1:  # the second epoch of each probe stage
        timed["simple" if "simple" in r["stage_name"] else "stack"] = r["seconds"] / max(1, r["timed_steps"])
        if i < len(seen):
            overheads.append(max(0.0, seen[i] - seen[i - 1] - r["seconds"]))
# No record seen in time (a probe faster than the polling): one second per epoch, a checkpoint's order of magnitude.
print(timed["simple"], timed["stack"], max(overheads) if overheads else 1.0)
EOF
}

phase_train() {
  [[ -x "$DVSO" && -d "$DATA/heldout_all" ]] || fail "run the prepare phase first (no $DVSO or no data in $DATA)"
  (( $(seconds_left) - EVAL_RESERVE_SECONDS > 90 )) ||
    fail "only $(seconds_left) s left: call again at once with 'TOTAL_SECONDS=T $0 train' (build and data stay)"
  local simple_s stack_s overhead_s
  read -r simple_s stack_s overhead_s < <(measure_step_seconds) || true
  [[ -n "${overhead_s:-}" ]] || fail "the probe training gave no step times ($DATA/probe/train.log)"
  local budget=$(( $(seconds_left) - EVAL_RESERVE_SECONDS ))
  (( budget > 20 )) || fail "only $budget s left for training after the probe"
  log "step time: SimpleNet $simple_s s, StackNet $stack_s s, $overhead_s s per epoch besides; $budget s for training"
  # A fresh run folder: the export and evaluation steps of train_stacknet.sh keep what an earlier run left there.
  rm -rf "$RUN" && mkdir -p "$RUN"
  local scaled
  scaled=$("$PYTHON" scripts/gpu/stage_steps.py scale "$CONFIG" "$RUN/config_scaled.yaml" "$simple_s" "$stack_s" \
    "$budget" "$overhead_s")
  log "$scaled ($RUN/config_scaled.yaml)"
  # The learning curve (held-out abs rel after every epoch) beside the training, as the CPU pipeline does; in a
  # session of its own, so that stopping it stops its exports and predictions too.
  rm -f "$RUN/train.done" "$RUN/curve.csv"
  setsid env DVSO="$DVSO" RUN="$RUN" NICE=0 scripts/train_stacknet.sh monitor > "$RUN/curve_monitor.log" 2>&1 &
  local monitor=$! train_start=$SECONDS status=0
  # The schedule is sized to the budget; the time limit is the guarantee. SIGINT makes `dvso train` write
  # checkpoint_last.pt after the current step and stop.
  timeout -k 20 -s INT "$(( $(seconds_left) - EVAL_RESERVE_SECONDS ))" \
    "$DVSO" train --config "$RUN/config_scaled.yaml" --output-dir "$RUN" > "$RUN/train.log" 2>&1 || status=$?
  touch "$RUN/train.done"
  sleep 5  # a few seconds for a curve row the monitor is writing; it may not hold up the rest
  kill -- "-$monitor" 2>/dev/null || true
  # The monitor polls every 30 s and may be stopped mid-work: drop a row it did not finish (the curve figure
  # refuses one).
  if [[ -s "$RUN/curve.csv" && $(tail -c 1 "$RUN/curve.csv" | od -An -c | tr -d ' ') != '\n' ]]; then
    sed -i '$d' "$RUN/curve.csv"
  fi
  local ckpt=$RUN/checkpoint_final.pt complete=true
  if [[ ! -f "$ckpt" ]]; then
    ckpt=$RUN/checkpoint_last.pt complete=false
    [[ -f "$ckpt" ]] || { tail -20 "$RUN/train.log" >&2; fail "training left no checkpoint (status $status)"; }
    log "the schedule did not finish (status $status, time limit: 124): its last checkpoint is the model"
  fi
  log "trained in $((SECONDS - train_start)) s; $(tail -1 "$RUN/epochs.jsonl" | cut -c1-200)"

  # What comes back (at most 8 files of <= 16 MiB), packed first so that a failure or the tool's time limit in the
  # evaluation below cannot lose it. The model travels as a weights-only checkpoint in 15 MiB parts, not as this
  # machine's TorchScript file: `dvso export` here, with Debian's LibTorch 1.13 (scripts/gpu/collect_model.sh),
  # makes the file that every other machine loads (a TorchScript file written by a newer LibTorch need not load in
  # an older one), with the training camera this machine records in its export.
  "$DVSO" export --checkpoint "$ckpt" --weights-only --out "$RUN/weights_final.pt" > /dev/null
  split -b 15M -d "$RUN/weights_final.pt" "$OUT/weights_final.pt.part"
  # auto: StackNet when the schedule reached its StackNet stages, else SimpleNet (result.json's model_kind).
  "$DVSO" export --checkpoint "$ckpt" --model auto --out "$RUN/stacknet.pt" > /dev/null
  write_result() {  # $OUT/result.json: checksum, training camera, whether the schedule finished, metrics if any
    "$PYTHON" - "$RUN" "$OUT/result.json" "$(sha256sum "$RUN/weights_final.pt" | cut -d' ' -f1)" "$complete" <<'EOF'
import json, os, sys, zipfile
run, out, sha, complete = sys.argv[1:5]
with zipfile.ZipFile(f"{run}/stacknet.pt") as z:  # a TorchScript file is a zip; extra files sit under <name>/extra/
    metadata = json.loads(z.read(next(n for n in z.namelist() if n.endswith("/extra/dvso_metadata.json"))))
metrics_path = f"{run}/docs/stacknet_metrics.json"
metrics = json.load(open(metrics_path)) if os.path.exists(metrics_path) else None
json.dump({"weights_sha256": sha, "schedule_complete": complete == "true", "model_metadata": metadata,
           "metrics": metrics}, open(out, "w"), indent=1)
EOF
  }
  write_result
  pack_logs() {
    cp "$LOG" "$RUN/device_log.txt"
    local files=() f
    for f in config_scaled.yaml epochs.jsonl losses.csv train.log curve.csv curve_monitor.log eval.log docs \
             device_log.txt; do
      if [[ -e "$RUN/$f" ]]; then files+=("$f"); fi
    done
    tar -C "$RUN" -czf "$OUT/run_logs.tgz" "${files[@]}"
  }
  pack_logs
  log "weights packed ($(ls "$OUT" | tr '\n' ' '))"
  "$DVSO" export --checkpoint "$ckpt" --model simple --out "$RUN/simplenet.pt" > /dev/null ||
    log "SimpleNet export failed"

  # Evaluation on the held-out worlds, bounded by what is left before the tool's limit; a failure here is logged.
  local eval_limit=$(( TOTAL_SECONDS + 25 - (SECONDS - START) ))
  if (( eval_limit > 10 )) && timeout -k 5 "$eval_limit" env DVSO="$DVSO" CONFIG="$RUN/config_scaled.yaml" \
       RUN="$RUN" FINETUNE_CONFIG="" DOCS="$RUN/docs" NICE=0 scripts/train_stacknet.sh eval > "$RUN/eval.log" 2>&1; then
    local heldout
    heldout=$(cd "$RUN" && "$PYTHON" -c "import json; m = json.load(open('docs/stacknet_metrics.json'))['stacknet']['all']
print('abs rel %.4f d1 %.3f' % (m['abs_rel'], m['a1']))")
    log "held-out, model as trained ($heldout)"
  else
    log "evaluation failed or ran out of time (eval.log in run_logs.tgz): $(tail -3 "$RUN/eval.log" | tr '\n' ' ')"
  fi
  if [[ $REQUIRE_CUDA == 1 ]] && (( $(seconds_left) > 0 )); then
    local latency
    latency=$(timeout 30 "$DVSO" bench --model "$RUN/stacknet.pt" --device cuda --dtype all --runs 50 --json |
      tr -d '\n ' || echo failed)
    log "GPU latency of the new StackNet: $latency"
  fi
  write_result || log "result.json not updated"
  pack_logs || log "run_logs.tgz not updated"
  log "done in $((SECONDS - START)) s: $(ls "$OUT" | tr '\n' ' ')"
}

case "$PHASE" in
  all) phase_prepare; log "$(seconds_left) s left"; phase_train ;;
  prepare) phase_prepare; log "$(seconds_left) s left" ;;
  train)
    # A train call follows a prepare call on the same machine: its clock must be the session's, not a fresh 560 s.
    [[ -n "${TOTAL_SECONDS_GIVEN:-}" ]] ||
      fail "the train phase needs TOTAL_SECONDS (the device time left minus ~60 s: budget_left_s from status)"
    phase_train ;;
  *) echo "usage: $0 [all|prepare|train]" >&2; exit 2 ;;
esac

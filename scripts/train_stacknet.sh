#!/usr/bin/env bash
# The paper's label-to-model pipeline, end to end, resumable at every step
# (a step whose output is complete is skipped; training continues with --resume):
#   1. render simulated training sequences along KITTI trajectories 00-07
#      (`dvso simulate --appearance varied`, one world seed per segment) and
#      held-out sequences along 08, 09, 10 (seeds never trained on);
#   2. sparse supervision with Stereo DSO labels (`dvso labels`, paper section 4);
#   3. train the staged config (`dvso train`, configs/stacknet_cpu_v4_long.yaml), with a
#      held-out abs rel after every epoch (learning curve);
#   4. export SimpleNet (after its stages) and StackNet (final);
#   5. for the shipped chain, fine-tune that export at 640x192 ($FINETUNE_CONFIG, `train --init-from`)
#      into $RUN/finetune and export again;
#   6. tb: render four 1241x376 worlds along training trajectories (seeds never used for the network) and
#      grid-search the virtual baseline with `dvso tune-baseline`, which stamps it into the final model
#      ($FINAL_RUN/stacknet_tb.pt: the file to copy to models/stacknet_cpu_main.pt);
#   7. evaluate both on the held-out frames (`dvso eval-depth`, 0-80 m) and write
#      docs/stacknet_metrics.json, docs/stacknet_heldout.png (image / GT / SimpleNet /
#      StackNet), docs/stacknet_learning_curve.{csv,png}; the real KITTI 2015 pair in data/ (abs rel, a
#      domain-gap figure) and docs/stacknet_real.png.
#
#   scripts/train_stacknet.sh [all|data|train|monitor|export|finetune|tb|eval]    (default: all)
# Environment:
#   DVSO=build/dvso                      binary (build with scripts/build.sh)
#   WORLDS=v4                            training worlds: v4 = 72 of 30 frames, v3 = 36 of 60 frames,
#                                        v4c = v4's worlds with detailed car paint (session 36),
#                                        v4c2 = v4c's as simulator world version 2 (altitude drift corrected, session 39),
#                                        smoke = 3 of 12 frames (tests of the scripts only)
#   CONFIG=configs/stacknet_cpu_v4_long.yaml  (the shipped model's base run; v3: configs/stacknet_cpu_main.yaml;
#                                        v4c: configs/stacknet_cpu_v4c_long.yaml; v4c2: configs/stacknet_cpu_v4c2_long.yaml);
#                                        its data paths must point into $DATA
#   CAR_DETAIL=0                         `dvso simulate --car-detail` of every world (training, held-out, tb): 0 = plain
#                                        paint, the worlds of every model before session 36 (v3, v4, smoke); -1 = the
#                                        varied look's own share (the default of v4c and v4c2)
#   WORLD_VERSION=1 (v3, v4, v4c), 2 (v4c2)  `dvso simulate --world-version` of every world (core/simulator.h): these sets
#                                        are the worlds their models were trained on, rendered again exactly; others
#                                        (smoke) default to the binary's current version. A cached world of another
#                                        version is an error in every step that renders or reads worlds (smoke: it
#                                        is rendered again). Needs a dvso built since session 39 (--world-version).
#   DATA=/tmp/dvso_stacknet_$WORLDS      rendered sequences and labels (~6 GB)
#   RUN=$DATA/run_main                   checkpoints, logs, exported models, predictions
#   FINETUNE_CONFIG=configs/stacknet_cpu_v4_finetune_640.yaml  second training from the base run's export
#                                        (default for the shipped config; "" = none: the base run is final)
#   TB_VALUES=0.40:0.04:0.64             b_v grid of the tb step (metres)
#   TB_FINE_STEP=0.01                    then a grid of this step around the coarse best, 3 steps each side
#                                        ("" = coarse grid only; before session 33 there was none)
#   DOCS=docs                            where metrics and figures go (default: docs/ for the shipped
#                                        model's config, $RUN/docs for any other)
#   SNIPPETS=/work/shared/data/kitti_odometry_snippets  real KITTI frames (no depth GT) for a figure
#   NICE=19                              niceness of the heavy steps (the machine is shared)
#   JOBS=1                               worlds rendered and labelled at once in the data step
#   REPO=(script's parent)               repository root (when running a copy of this script)
# Ablation (documented, not the paper's way): CONFIG=configs/stacknet_cpu_main_gt.yaml
# trains on GT samples (simulator disp_0, 2 %) instead of Stereo DSO labels;
# CONFIG=configs/stacknet_cpu_main_self.yaml trains self-supervised only (no L_S).
set -euo pipefail
cd "${REPO:-$(dirname "$0")/..}"
STEP=${1:-all}
# shellcheck source=world_version.sh
source scripts/world_version.sh
DVSO=${DVSO:-build/dvso}
WORLDS=${WORLDS:-v4}
# The shipped models/stacknet_cpu_main.pt (session 13) is this config's run (session 9) fine-tuned at 640x192 by
# configs/stacknet_cpu_v4_finetune_640.yaml (the finetune step), with b_v from the tb step.
SHIPPED_CONFIG=configs/stacknet_cpu_v4_long.yaml
V4C_CONFIG=configs/stacknet_cpu_v4c_long.yaml
V4C2_CONFIG=configs/stacknet_cpu_v4c2_long.yaml
case $WORLDS in
  v4) DEFAULT_CONFIG=$SHIPPED_CONFIG ;;
  v4c) DEFAULT_CONFIG=$V4C_CONFIG ;;
  v4c2) DEFAULT_CONFIG=$V4C2_CONFIG ;;
  *) DEFAULT_CONFIG=configs/stacknet_cpu_main.yaml ;;
esac
CONFIG=${CONFIG:-$DEFAULT_CONFIG}
CAR_DETAIL=${CAR_DETAIL:-$([[ $WORLDS == v4c* ]] && echo -1 || echo 0)}
case $WORLDS in
  v3 | v4 | v4c) WORLD_VERSION=${WORLD_VERSION:-1} ;;
  v4c2) WORLD_VERSION=${WORLD_VERSION:-2} ;;
  *) WORLD_VERSION=${WORLD_VERSION:-} ;;  # empty: the binary's current one (below)
esac
DATA=${DATA:-/tmp/dvso_stacknet_$WORLDS}
RUN=${RUN:-$DATA/run_main}
if [[ -z "${FINETUNE_CONFIG+set}" ]]; then
  case $CONFIG in
    "$SHIPPED_CONFIG") FINETUNE_CONFIG=configs/stacknet_cpu_v4_finetune_640.yaml ;;
    "$V4C_CONFIG") FINETUNE_CONFIG=configs/stacknet_cpu_v4c_finetune_640.yaml ;;
    "$V4C2_CONFIG") FINETUNE_CONFIG=configs/stacknet_cpu_v4c2_finetune_640.yaml ;;
    *) FINETUNE_CONFIG="" ;;
  esac
fi
# The run whose models are evaluated, tuned and shipped.
FINAL_RUN=$RUN
[[ -n "$FINETUNE_CONFIG" ]] && FINAL_RUN=$RUN/finetune
TB_VALUES=${TB_VALUES:-0.40:0.04:0.64}
TB_FINE_STEP=${TB_FINE_STEP-0.01}
# Figures and metrics go into docs/ only for the shipped model's config; other runs keep theirs in $RUN/docs.
DOCS=${DOCS:-$([[ $CONFIG == "$SHIPPED_CONFIG" ]] && echo docs || echo "$RUN/docs")}
NICE=${NICE:-19}
JOBS=${JOBS:-1}  # worlds rendered and labelled at once in the data step (the GPU machine has 16 cores)
FIGURES=${FIGURES:-$(dirname "$DVSO")/tools/stacknet_figures}
SNIPPETS=${SNIPPETS:-/work/shared/data/kitti_odometry_snippets}
RENDER_W=640
RENDER_H=192
run() { nice -n "$NICE" "$@"; }
log() { echo "[$(date -u +%H:%M:%S)] $*"; }
[[ -x "$DVSO" ]] || { echo "error: $DVSO not found (build first: scripts/build.sh)" >&2; exit 1; }
# The world version this run renders and reads, from here on fixed.
if [[ -z $WORLD_VERSION ]]; then WORLD_VERSION=$(binary_world_version "$DVSO"); fi

# name  pose file  first pose  frames  world seed. Training: 00-07; held out: 08-10.
# 36 worlds of 60 frames (2160 training frames), spread evenly along each trajectory (worlds per
# trajectory ~ its length). Many short worlds instead of few long ones: with 14 worlds of 150-250
# frames the training loss kept falling while the held-out abs rel stayed flat from step 750 on
# (docs/stacknet.md), i.e. the network fitted each world's look instead of depth cues.
TRAIN_SEGMENTS=(
  "w201 00 248 60 201" "w202 00 746 60 202" "w203 00 1244 60 203" "w204 00 1742 60 204"
  "w205 00 2240 60 205" "w206 00 2738 60 206" "w207 00 3236 60 207" "w208 00 3734 60 208"
  "w209 00 4232 60 209" "w210 01 173 60 210" "w211 01 520 60 211" "w212 01 867 60 212"
  "w213 02 255 60 213" "w214 02 766 60 214" "w215 02 1278 60 215" "w216 02 1789 60 216"
  "w217 02 2300 60 217" "w218 02 2811 60 218" "w219 02 3322 60 219" "w220 02 3834 60 220"
  "w221 02 4345 60 221" "w222 03 185 60 222" "w223 03 555 60 223" "w224 04 105 60 224"
  "w225 05 225 60 225" "w226 05 675 60 226" "w227 05 1125 60 227" "w228 05 1575 60 228"
  "w229 05 2025 60 229" "w230 05 2475 60 230" "w231 06 173 60 231" "w232 06 520 60 232"
  "w233 06 867 60 233" "w234 07 173 60 234" "w235 07 520 60 235" "w236 07 867 60 236"
)
# World set v4 (WORLDS=v4, session 8): the same 2160 training frames spread over twice as many worlds
# (72 of 30 frames, seeds 401-472, worlds per trajectory ~ its length, evenly spaced along it), to test
# whether more looks beat more frames per look. Measured: they do not (held-out abs rel 0.2501 vs 0.2422
# for v3, docs/stacknet.md), so v3 stays the shipped model's data.
if [[ $WORLDS == v4 || $WORLDS == v4c || $WORLDS == v4c2 ]]; then
  mapfile -t TRAIN_SEGMENTS < <(python3 - <<'EOF'
lengths = {"00": 4541, "01": 1101, "02": 4661, "03": 801, "04": 271, "05": 2761, "06": 1101, "07": 1101}
worlds, frames, total = 72, 30, sum(lengths.values())
# Largest-remainder allocation of the worlds to trajectories, at least one each.
quota = {t: worlds * n / total for t, n in lengths.items()}
count = {t: max(1, int(q)) for t, q in quota.items()}
for t in sorted(quota, key=lambda t: quota[t] - int(quota[t]), reverse=True)[: worlds - sum(count.values())]:
    count[t] += 1
seed = 401
for t, n in lengths.items():
    for k in range(count[t]):
        first = max(0, min(n - frames, int((k + 0.5) * n / count[t]) - frames // 2))
        print(f"w{seed} {t} {first} {frames} {seed}")
        seed += 1
EOF
  )
fi
TEST_SEGMENTS=("te08 08 1000 150 308" "te09 09 300 150 309" "te10 10 300 150 310")
# WORLDS=smoke: a few short worlds, for testing this script and scripts/gpu/train_on_device.sh on a machine
# without a GPU (configs/stacknet_gpu_smoke.yaml trains on them); no model from them means anything.
if [[ $WORLDS == smoke ]]; then
  TRAIN_SEGMENTS=("w901 00 248 12 901" "w902 05 225 12 902" "w903 07 173 12 903")
  TEST_SEGMENTS=("te08 08 1000 10 308" "te09 09 300 10 309" "te10 10 300 10 310")
fi
# Held-out frames of the figure docs/stacknet_heldout.png.
FIGURE_FRAMES=(te08_000030 te08_000110 te09_000070 te10_000120)
[[ $WORLDS == smoke ]] && FIGURE_FRAMES=(te08_000005 te09_000005 te10_000005)
# tb worlds (paper: b_v tuned on training sequences): KITTI-size grey sequences along training trajectories,
# seeds used neither for the network nor for the held-out worlds (docs/dvso.md, session 13).
TB_WORLDS=("tb05 05 1000 300 9505" "tb00 00 3000 300 9701" "tb02 02 1500 300 9702" "tb07 07 600 300 9703")
# Frames of each held-out segment used for the per-epoch curve (every 5th: 90 frames).
CURVE_STEP=5

# Returns 0 when world `name` is complete and $WORLD_VERSION, 1 when it is absent; a complete world of another
# version is an error (training on it would mix worlds), except for WORLDS=smoke, whose worlds only test this script
# and are rendered again.
cached_world_is_current() {  # name
  local yaml="$DATA/$1/simulation.yaml"  # written after the last frame
  [[ -f $yaml ]] || return 1
  local recorded
  recorded=$(recorded_world_version "$yaml")
  [[ $recorded == "$WORLD_VERSION" ]] && return 0
  if [[ $WORLDS == smoke ]]; then
    rm -rf "${DATA:?}/$1"
    return 1
  fi
  echo "error: $DATA/$1 is simulator world version $recorded, this run wants version $WORLD_VERSION: delete it (with the runs" \
    "trained on it) to render it again, or set WORLD_VERSION=$recorded to use it as it is" >&2
  exit 1
}

# The worlds a step reads must be there, complete and $WORLD_VERSION: the held-out ones, and with `all` the training
# ones too (train and finetune; eval reads only the held-out ones, so pruned training worlds do not stop it).
check_cached_worlds() {  # [all]
  local spec segments=("${TEST_SEGMENTS[@]}")
  [[ ${1:-} == all ]] && segments+=("${TRAIN_SEGMENTS[@]}")
  for spec in "${segments[@]}"; do
    set -- $spec
    cached_world_is_current "$1" ||
      { echo "error: $DATA/$1 is missing or incomplete: run the data step first" >&2; exit 1; }
  done
}

# Renders world `name` into $DATA/name unless complete; extra arguments go to `dvso simulate`.
simulate_world() {  # name pose first count seed [simulate options...]
  local name=$1 pose=$2 first=$3 count=$4 seed=$5
  shift 5
  cached_world_is_current "$name" && return 0
  log "simulate $name (KITTI $pose from pose $first, $count frames, seed $seed, world version $WORLD_VERSION) $*"
  run "$DVSO" simulate --out "$DATA/$name" --trajectory "data/kitti_poses/$pose.txt" --first "$first" --count "$count" \
    --seed "$seed" --appearance varied --car-detail "$CAR_DETAIL" --world-version "$WORLD_VERSION" "$@" --quiet \
    > "$DATA/$name.simulate.log"
}

render() {  # name pose first count seed: a training or held-out world at the network's size, colour
  # Training worlds also vary the street layout (building, car, tree density drawn from the
  # seed); held-out worlds keep the simulator's defaults, so no held-out look was chosen.
  local layout=()
  if [[ $1 == w* ]]; then
    layout=(--building-density "0.$((40 + $5 * 37 % 56))" --car-density "0.$((25 + $5 * 53 % 66))"
            --tree-density "$(( $5 * 29 % 13 / 10 )).$(( $5 * 29 % 13 % 10 ))")
  fi
  simulate_world "$@" --width $RENDER_W --height $RENDER_H --color "${layout[@]}"
}

label() {  # name
  local seq="$DATA/$1"
  [[ -s "$seq/labels_summary.json" ]] && return 0  # written when every frame is labelled
  log "labels $1"
  run "$DVSO" labels --sequence "$seq" --out "$seq/labels" --gt-disparity "$seq/disp_0" --json --quiet \
    > "$seq/labels_summary.json.tmp"
  mv "$seq/labels_summary.json.tmp" "$seq/labels_summary.json"
}

# Runs "$@" in the background, at most $JOBS at once; wait_all waits for each and fails if any failed. (Polling
# instead of `wait -n`: a status that `wait -n` collected is gone for the `wait PID` that counts failures.)
BACKGROUND=()
in_background() {
  while (( $(jobs -rp | wc -l) >= JOBS )); do sleep 1; done
  "$@" &
  BACKGROUND+=($!)
}
wait_all() {
  local failed=0 pid
  for pid in "${BACKGROUND[@]}"; do wait "$pid" || failed=$((failed + 1)); done
  BACKGROUND=()
  (( failed == 0 )) || { echo "error: $failed of the parallel data jobs failed (logs in $DATA)" >&2; exit 1; }
}

world_data() {  # name pose first count seed: render a world, then label it when it is a training world
  render "$@"
  if [[ $1 == w* ]]; then label "$1"; fi
}

step_data() {
  mkdir -p "$DATA"
  # Longest first (the held-out worlds have 5x the frames), so the last job to start is a short one.
  for spec in "${TEST_SEGMENTS[@]}" "${TRAIN_SEGMENTS[@]}"; do in_background world_data $spec; done
  wait_all
  # Held-out image/GT folders with unique names (for one eval-depth over all three).
  for split in all curve; do
    local img="$DATA/heldout_$split/image" gt="$DATA/heldout_$split/gt"
    [[ -f "$DATA/heldout_$split/done" ]] && continue
    rm -rf "$DATA/heldout_$split" && mkdir -p "$img" "$gt"
    for spec in "${TEST_SEGMENTS[@]}"; do
      set -- $spec
      local step=1
      [[ $split == curve ]] && step=$CURVE_STEP
      for ((i = 0; i < $4; i += step)); do
        local f
        f=$(printf %06d "$i")
        ln -s "$DATA/$1/image_2/$f.png" "$img/$1_$f.png"
        ln -s "$DATA/$1/disp_0/$f.png" "$gt/$1_$f.png"
      done
    done
    cp "$DATA/te08/calib.txt" "$DATA/heldout_$split/calib.txt"  # same camera for all
    touch "$DATA/heldout_$split/done"
  done
}

# Held-out abs rel of a checkpoint on the curve frames: prints one JSON object.
curve_eval() {  # checkpoint tag
  local dir="$RUN/curve/$2"
  mkdir -p "$dir"
  run "$DVSO" export --checkpoint "$1" --model auto --out "$dir/model.pt" > /dev/null
  run "$DVSO" predict --model "$dir/model.pt" --images "$DATA/heldout_curve/image" --out "$dir/pred" --no-color \
    > /dev/null
  run "$DVSO" eval-depth --pred "$dir/pred/left" --gt "$DATA/heldout_curve/gt" --calib "$DATA/heldout_curve/calib.txt" \
    --max-depth 80 --json
  rm -rf "$dir"
}

# One learning-curve CSV row from an epochs.jsonl record, its index and (optional) eval-depth JSON.
curve_row() {  # record index metrics
  python3 - "$1" "$2" "${3:-}" <<'EOF'
import json, sys
r = json.loads(sys.argv[1])
m = json.loads(sys.argv[3]) if sys.argv[3].strip() else {}
metrics = ["%.4f" % m[k] if k in m else "" for k in ("abs_rel", "sq_rel", "rmse", "a1")]
print(",".join([sys.argv[2], str(r["stage"]), r["stage_name"], str(r["global_step"]), "%.5f" % r["mean_total"],
                "%.5f" % r["mean_supervised"], "%.5f" % r["mean_unsupervised"]] + metrics))
EOF
}

# Follows a running training: after each epoch's checkpoint, evaluates it and
# appends a row to $RUN/curve.csv (epoch line, stage, step, loss, held-out metrics).
# Epochs whose checkpoint was already overwritten get the loss only.
curve_monitor() {
  local csv="$RUN/curve.csv" done_rows lines metrics ck="$RUN/curve_checkpoint.pt"
  [[ -f "$csv" ]] || echo "epoch,stage,stage_name,global_step,mean_total,mean_supervised,mean_unsupervised,abs_rel,sq_rel,rmse,a1" > "$csv"
  while true; do
    done_rows=$(($(wc -l < "$csv") - 1))
    lines=0
    [[ -f "$RUN/epochs.jsonl" ]] && lines=$(wc -l < "$RUN/epochs.jsonl")
    if (( lines > done_rows )) && [[ "$RUN/checkpoint_last.pt" -nt "$RUN/epochs.jsonl" ]]; then
      cp "$RUN/checkpoint_last.pt" "$ck"
      while (( done_rows < lines - 1 )); do
        curve_row "$(sed -n "$((done_rows + 1))p" "$RUN/epochs.jsonl")" "$done_rows" >> "$csv"
        done_rows=$((done_rows + 1))
      done
      metrics=$(curve_eval "$ck" "epoch$lines" || echo "")
      curve_row "$(sed -n "${lines}p" "$RUN/epochs.jsonl")" "$((lines - 1))" "$metrics" >> "$csv"
      rm -f "$ck"
      log "curve: $(tail -1 "$csv")"
    fi
    lines=0
    [[ -f "$RUN/epochs.jsonl" ]] && lines=$(wc -l < "$RUN/epochs.jsonl")
    if [[ -f "$RUN/checkpoint_final.pt" || -f "$RUN/train.done" ]] && (( lines <= $(wc -l < "$csv") - 1 )); then
      break
    fi
    sleep 30
  done
}

# Trains $CONFIG into $RUN (from the weights of $INIT_FROM when set), resuming an interrupted run.
step_train() {
  mkdir -p "$RUN"
  if [[ -f "$RUN/checkpoint_final.pt" ]]; then log "training $RUN already finished"; return 0; fi
  check_cached_worlds all
  local resume=()
  [[ -f "$RUN/checkpoint_last.pt" ]] && resume=(--resume)
  [[ -n "${INIT_FROM:-}" ]] && resume+=(--init-from "$INIT_FROM")  # ignored by train when resuming
  rm -f "$RUN/train.done"  # marks the end of this training process (stops the curve monitor)
  log "train $CONFIG -> $RUN ${resume[*]:-}"
  curve_monitor >> "$RUN/curve_monitor.log" 2>&1 &
  local monitor=$!
  # A failed or interrupted training (set -e, Ctrl-C) must not leave the monitor polling forever (a rerun
  # would start a second one writing the same curve rows).
  trap "touch '$RUN/train.done'; kill $monitor 2>/dev/null || true" EXIT
  local start=$SECONDS
  run "$DVSO" train --config "$CONFIG" --output-dir "$RUN" "${resume[@]}" >> "$RUN/train.log" 2>&1
  echo "$((SECONDS - start))" >> "$RUN/train_seconds.txt"
  wait "$monitor" || true
  trap - EXIT
  touch "$RUN/train.done"
}

step_export() {
  [[ -f "$RUN/checkpoint_final.pt" ]] || { echo "error: no final checkpoint in $RUN (train first)" >&2; exit 1; }
  # SimpleNet is frozen during the StackNet stages, so the final checkpoint holds it exactly as its
  # own stages left it, whatever the number of stages of the config.
  [[ -f "$RUN/simplenet.pt" ]] || run "$DVSO" export --checkpoint "$RUN/checkpoint_final.pt" --model simple --out "$RUN/simplenet.pt"
  [[ -f "$RUN/stacknet.pt" ]] || run "$DVSO" export --checkpoint "$RUN/checkpoint_final.pt" --model stack --out "$RUN/stacknet.pt"
}

# Second training from the base run's StackNet export (the shipped chain), then its export.
step_finetune() {
  if [[ -z "$FINETUNE_CONFIG" ]]; then log "no FINETUNE_CONFIG: the base run is final"; return 0; fi
  [[ -f "$RUN/stacknet.pt" ]] || { echo "error: no $RUN/stacknet.pt to fine-tune (train and export first)" >&2; exit 1; }
  local base_model=$RUN/stacknet.pt
  RUN=$FINAL_RUN CONFIG=$FINETUNE_CONFIG INIT_FROM=$base_model step_train
  RUN=$FINAL_RUN step_export
}

# tb: b_v grid search on the tb worlds; writes $FINAL_RUN/stacknet_tb.pt (the model with b_v in its metadata).
step_tb() {
  [[ -f "$FINAL_RUN/stacknet.pt" ]] || { echo "error: no $FINAL_RUN/stacknet.pt (export first)" >&2; exit 1; }
  [[ -f "$FINAL_RUN/stacknet_tb.pt" ]] && { log "tb already done: $FINAL_RUN/stacknet_tb.pt"; return 0; }
  local pairs=()
  for spec in "${TB_WORLDS[@]}"; do
    set -- $spec
    simulate_world "$@"  # the simulator's default camera: KITTI's 1241x376 grey
    pairs+=(--sequence "$DATA/$1" --gt "$DATA/$1/poses.txt")
  done
  log "tune-baseline $TB_VALUES on ${#TB_WORLDS[@]} worlds"
  rm -rf "$FINAL_RUN/tb" "$FINAL_RUN/tb_fine"
  run "$DVSO" tune-baseline --model "$FINAL_RUN/stacknet.pt" "${pairs[@]}" --values "$TB_VALUES" --out "$FINAL_RUN/tb" \
    --write-model "$FINAL_RUN/stacknet_tb.pt.tmp" --json > "$FINAL_RUN/tune_baseline.json"
  if [[ -n "$TB_FINE_STEP" ]]; then
    # The coarse grid's step (0.04 m, ~8 % of b_v) is coarser than the scale errors that matter (t_rel <= 2 %):
    # a second grid of TB_FINE_STEP around the coarse best, three steps to each side.
    local best fine
    best=$(sed -n 's/.*"best_virtual_baseline": *\([0-9.eE+-]*\).*/\1/p' "$FINAL_RUN/tune_baseline.json")
    [[ -n "$best" ]] || { echo "error: no best_virtual_baseline in $FINAL_RUN/tune_baseline.json" >&2; exit 1; }
    fine=$(awk -v b="$best" -v s="$TB_FINE_STEP" 'BEGIN { printf "%.3f:%.3f:%.3f", b - 3 * s, s, b + 3 * s }')
    log "tune-baseline $fine (around the coarse best $best)"
    run "$DVSO" tune-baseline --model "$FINAL_RUN/stacknet.pt" "${pairs[@]}" --values "$fine" --out "$FINAL_RUN/tb_fine" \
      --write-model "$FINAL_RUN/stacknet_tb.pt.tmp" --json > "$FINAL_RUN/tune_baseline_fine.json"
  fi
  mv "$FINAL_RUN/stacknet_tb.pt.tmp" "$FINAL_RUN/stacknet_tb.pt"
  log "tuned model: $FINAL_RUN/stacknet_tb.pt (ship: cp it to models/stacknet_cpu_main.pt)"
}

step_eval() {
  local RUN=$FINAL_RUN  # evaluate the final models (the fine-tune's when there is one)
  check_cached_worlds
  mkdir -p "$DOCS"  # the only step that writes there
  local results=()
  for net in simplenet stacknet; do
    local pred="$RUN/pred_$net"
    if [[ ! -f "$pred/done" ]]; then
      rm -rf "$pred"
      run "$DVSO" predict --model "$RUN/$net.pt" --images "$DATA/heldout_all/image" --out "$pred" --no-color
      touch "$pred/done"
    fi
    run "$DVSO" eval-depth --pred "$pred/left" --gt "$DATA/heldout_all/gt" --calib "$DATA/heldout_all/calib.txt" \
      --max-depth 80 --json > "$RUN/metrics_$net.json"
    # The signed bias by range at textured pixels, no depth cap: what DVSO's scale follows (docs/evaluation.md).
    run "$DVSO" eval-depth --pred "$pred/left" --gt "$DATA/heldout_all/gt" --calib "$DATA/heldout_all/calib.txt" \
      --max-depth 1000 --ranges 0,5,10,20,40,80,1000 --images "$DATA/heldout_all/image" --min-gradient 100 --json \
      > "$RUN/metrics_${net}_ranges.json"
    for spec in "${TEST_SEGMENTS[@]}"; do
      set -- $spec
      local sub="$RUN/pred_${net}_$1"
      rm -rf "$sub" && mkdir -p "$sub/pred" "$sub/gt"
      for f in "$pred/left/$1_"*.png; do ln -s "$(realpath "$f")" "$sub/pred/$(basename "$f")"; done
      for f in "$DATA/heldout_all/gt/$1_"*.png; do ln -s "$(realpath "$f")" "$sub/gt/$(basename "$f")"; done
      run "$DVSO" eval-depth --pred "$sub/pred" --gt "$sub/gt" --calib "$DATA/heldout_all/calib.txt" --max-depth 80 \
        --json > "$RUN/metrics_${net}_$1.json"
      rm -rf "$sub"
    done
  done
  # Real images (domain gap): the KITTI 2015 pair with its GT, and the real odometry snippets (no depth GT).
  local k15=data/kitti_stereo_2015_sample
  for net in simplenet stacknet; do
    run "$DVSO" predict --model "$RUN/$net.pt" --images "$k15/image_2" --out "$RUN/real_k15_$net" > /dev/null
    run "$DVSO" eval-depth --pred "$RUN/real_k15_$net/left" --gt "$k15/disp_occ_0" --kitti-focal --max-depth 80 \
      --json > "$RUN/metrics_k15_$net.json"
    if [[ -d "$SNIPPETS/a/image_0" ]]; then
      for s in a b; do
        run "$DVSO" predict --model "$RUN/$net.pt" --images "$SNIPPETS/$s/image_0" --out "$RUN/real_${s}_$net" > /dev/null
      done
    fi
  done
  python3 - "$RUN" "$DOCS/stacknet_metrics.json" "$CONFIG${FINETUNE_CONFIG:+, fine-tuned by $FINETUNE_CONFIG}" <<'EOF'
import json, sys, os
run, out, config = sys.argv[1:4]
result = {"config": config, "heldout": "dvso simulate --appearance varied along KITTI 08 (poses 1000-1149, seed 308), "
          "09 (300-449, seed 309), 10 (300-449, seed 310), 640x192; eval-depth 0-80 m, no crop, no median scaling"}
def summary(path):  # the per-image rows stay in RUN/metrics_*.json (they made this file 650 KB)
    return {k: v for k, v in json.load(open(path)).items() if k != "per_image"}
for net in ("simplenet", "stacknet"):
    result[net] = {"all": summary(f"{run}/metrics_{net}.json")}
    ranges = f"{run}/metrics_{net}_ranges.json"
    if os.path.exists(ranges):  # 0-1000 m, pixels with a Sobel gradient >= 100
        result[net]["textured_by_range"] = json.load(open(ranges))["ranges"]
    for seq in ("te08", "te09", "te10"):
        result[net][seq] = summary(f"{run}/metrics_{net}_{seq}.json")
    k15 = f"{run}/metrics_k15_{net}.json"
    if os.path.exists(k15):
        result[net]["kitti2015_000046_10"] = summary(k15)
secs = f"{run}/train_seconds.txt"
if os.path.exists(secs):
    result["train_wall_seconds"] = sum(int(l) for l in open(secs) if l.strip())
json.dump(result, open(out, "w"), indent=2)
print(json.dumps({k: result[k]["all"] for k in ("simplenet", "stacknet")}, indent=1))
EOF
  if [[ -x "$FIGURES" ]]; then
    local rows=()
    for f in "${FIGURE_FRAMES[@]}"; do
      rows+=(--row "$DATA/heldout_all/image/$f.png" "$DATA/heldout_all/gt/$f.png" "$RUN/pred_simplenet/left/$f.png"
             "$RUN/pred_stacknet/left/$f.png")
    done
    "$FIGURES" montage --out "$DOCS/stacknet_heldout.png" --titles "image,GT disparity,SimpleNet,StackNet" "${rows[@]}"
    rows=(--row "$k15/image_2/000046_10.png" "$k15/disp_occ_0/000046_10.png" "$RUN/real_k15_simplenet/left/000046_10.png"
          "$RUN/real_k15_stacknet/left/000046_10.png")
    if [[ -d "$SNIPPETS/a/image_0" ]]; then
      rows+=(--row "$SNIPPETS/a/image_0/000020.png" - "$RUN/real_a_simplenet/left/000020.png" "$RUN/real_a_stacknet/left/000020.png"
             --row "$SNIPPETS/b/image_0/000020.png" - "$RUN/real_b_simplenet/left/000020.png" "$RUN/real_b_stacknet/left/000020.png")
    fi
    "$FIGURES" montage --out "$DOCS/stacknet_real.png" --titles "real KITTI image,GT disparity,SimpleNet,StackNet" "${rows[@]}"
    [[ -f "$RUN/curve.csv" ]] && cp "$RUN/curve.csv" "$DOCS/stacknet_learning_curve.csv" &&
      "$FIGURES" curve --csv "$RUN/curve.csv" --out "$DOCS/stacknet_learning_curve.png"
  fi
  log "metrics in $DOCS/stacknet_metrics.json"
}

case "$STEP" in
  all) step_data; step_train; step_export; step_finetune; step_tb; step_eval ;;
  data) step_data ;;
  train) step_train ;;
  monitor) curve_monitor ;;  # the curve of a training started elsewhere
  export) step_export ;;
  finetune) step_finetune ;;
  tb) step_tb ;;
  eval) step_eval ;;
  *) echo "usage: $0 [all|data|train|monitor|export|finetune|tb|eval]" >&2; exit 2 ;;
esac

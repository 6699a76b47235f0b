#!/usr/bin/env bash
# The paper's label-to-model pipeline, end to end, resumable at every step
# (a step whose output is complete is skipped; training continues with --resume):
#   1. render simulated training sequences along KITTI trajectories 00-07
#      (`dvso simulate --appearance varied`, one world seed per segment) and
#      held-out sequences along 08, 09, 10 (seeds never trained on);
#   2. sparse supervision with Stereo DSO labels (`dvso labels`, paper section 4);
#   3. train the staged config (`dvso train`, configs/stacknet_cpu_main.yaml), with a
#      held-out abs rel after every epoch (learning curve);
#   4. export SimpleNet (after its stages) and StackNet (final);
#   5. evaluate both on the held-out frames (`dvso eval-depth`, 0-80 m) and write
#      docs/stacknet_metrics.json, docs/stacknet_heldout.png (image / GT / SimpleNet /
#      StackNet), docs/stacknet_learning_curve.{csv,png}; the real KITTI 2015 pair in data/ (abs rel, a
#      domain-gap figure) and docs/stacknet_real.png.
#
#   scripts/train_stacknet.sh [all|data|train|monitor|export|eval]    (default: all)
# Environment:
#   DVSO=build/dvso                      binary (build with scripts/build.sh)
#   CONFIG=configs/stacknet_cpu_main.yaml  its data paths must point into $DATA
#   DATA=/tmp/dvso_stacknet_v2           rendered sequences and labels (~6 GB)
#   RUN=$DATA/run_main                   checkpoints, logs, exported models, predictions
#   DOCS=docs                            where metrics and figures go
#   SNIPPETS=/work/shared/data/kitti_odometry_snippets  real KITTI frames (no depth GT) for a figure
#   NICE=19                              niceness of the heavy steps (the machine is shared)
#   REPO=(script's parent)               repository root (when running a copy of this script)
# Ablation (documented, not the paper's way): CONFIG=configs/stacknet_cpu_main_gt.yaml
# trains on GT samples (simulator disp_0, 2 %) instead of Stereo DSO labels;
# CONFIG=configs/stacknet_cpu_main_self.yaml trains self-supervised only (no L_S).
set -euo pipefail
cd "${REPO:-$(dirname "$0")/..}"
STEP=${1:-all}
DVSO=${DVSO:-build/dvso}
CONFIG=${CONFIG:-configs/stacknet_cpu_main.yaml}
DATA=${DATA:-/tmp/dvso_stacknet_v2}
RUN=${RUN:-$DATA/run_main}
DOCS=${DOCS:-docs}
NICE=${NICE:-19}
FIGURES=${FIGURES:-$(dirname "$DVSO")/tools/stacknet_figures}
SNIPPETS=${SNIPPETS:-/work/shared/data/kitti_odometry_snippets}
RENDER_W=640
RENDER_H=192
run() { nice -n "$NICE" "$@"; }
log() { echo "[$(date -u +%H:%M:%S)] $*"; }
[[ -x "$DVSO" ]] || { echo "error: $DVSO not found (build first: scripts/build.sh)" >&2; exit 1; }

# name  pose file  first pose  frames  world seed. Training: 00-07; held out: 08-10.
# 14 worlds, 2200 training frames, 450 held-out frames (sized for ~20 min of rendering and
# labelling on the shared 2-core machine).
TRAIN_SEGMENTS=(
  "tr00a 00 0 250 101"    "tr00b 00 1500 150 102" "tr00c 00 3000 150 103"
  "tr01a 01 100 150 104"
  "tr02a 02 500 150 105"  "tr02b 02 2000 150 106" "tr02c 02 3500 150 107"
  "tr03a 03 200 150 108"
  "tr04a 04 0 150 109"
  "tr05a 05 200 150 110"  "tr05b 05 1800 150 111"
  "tr06a 06 300 150 112"
  "tr07a 07 100 150 113"  "tr07b 07 700 150 114"
)
TEST_SEGMENTS=("te08 08 1000 150 308" "te09 09 300 150 309" "te10 10 300 150 310")
# Frames of each held-out segment used for the per-epoch curve (every 5th: 90 frames).
CURVE_STEP=5

render() {  # name pose first count seed
  local out="$DATA/$1"
  [[ -f "$out/simulation.yaml" ]] && return 0  # written after the last frame
  log "simulate $1 (KITTI $2 from pose $3, $4 frames, seed $5)"
  run "$DVSO" simulate --out "$out" --trajectory "data/kitti_poses/$2.txt" --first "$3" --count "$4" --seed "$5" \
    --width $RENDER_W --height $RENDER_H --color --appearance varied --quiet > "$DATA/$1.simulate.log"
}

label() {  # name
  local seq="$DATA/$1"
  [[ -s "$seq/labels_summary.json" ]] && return 0  # written when every frame is labelled
  log "labels $1"
  run "$DVSO" labels --sequence "$seq" --out "$seq/labels" --gt-disparity "$seq/disp_0" --json --quiet \
    > "$seq/labels_summary.json.tmp"
  mv "$seq/labels_summary.json.tmp" "$seq/labels_summary.json"
}

step_data() {
  mkdir -p "$DATA"
  for spec in "${TRAIN_SEGMENTS[@]}" "${TEST_SEGMENTS[@]}"; do render $spec; done
  for spec in "${TRAIN_SEGMENTS[@]}"; do set -- $spec; label "$1"; done
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

step_train() {
  mkdir -p "$RUN"
  if [[ -f "$RUN/checkpoint_final.pt" ]]; then log "training already finished"; return 0; fi
  local resume=()
  [[ -f "$RUN/checkpoint_last.pt" ]] && resume=(--resume)
  rm -f "$RUN/train.done"  # marks the end of this training process (stops the curve monitor)
  log "train $CONFIG -> $RUN ${resume[*]:-}"
  curve_monitor >> "$RUN/curve_monitor.log" 2>&1 &
  local monitor=$!
  local start=$SECONDS
  run "$DVSO" train --config "$CONFIG" --output-dir "$RUN" "${resume[@]}" >> "$RUN/train.log" 2>&1
  echo "$((SECONDS - start))" >> "$RUN/train_seconds.txt"
  wait "$monitor" || true
  touch "$RUN/train.done"
}

step_export() {
  local simple_stage
  simple_stage=$(ls "$RUN"/checkpoint_stage2_*.pt 2> /dev/null | head -1)
  [[ -n "$simple_stage" ]] || { echo "error: no SimpleNet stage checkpoint in $RUN" >&2; exit 1; }
  [[ -f "$RUN/simplenet.pt" ]] || run "$DVSO" export --checkpoint "$simple_stage" --model simple --out "$RUN/simplenet.pt"
  [[ -f "$RUN/stacknet.pt" ]] || run "$DVSO" export --checkpoint "$RUN/checkpoint_final.pt" --model stack --out "$RUN/stacknet.pt"
}

step_eval() {
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
  python3 - "$RUN" "$DOCS/stacknet_metrics.json" "$CONFIG" <<'EOF'
import json, sys, os
run, out, config = sys.argv[1:4]
result = {"config": config, "heldout": "dvso simulate --appearance varied along KITTI 08 (poses 1000-1149, seed 308), "
          "09 (300-449, seed 309), 10 (300-449, seed 310), 640x192; eval-depth 0-80 m, no crop, no median scaling"}
for net in ("simplenet", "stacknet"):
    result[net] = {"all": json.load(open(f"{run}/metrics_{net}.json"))}
    for seq in ("te08", "te09", "te10"):
        result[net][seq] = json.load(open(f"{run}/metrics_{net}_{seq}.json"))
    k15 = f"{run}/metrics_k15_{net}.json"
    if os.path.exists(k15):
        result[net]["kitti2015_000046_10"] = json.load(open(k15))
secs = f"{run}/train_seconds.txt"
if os.path.exists(secs):
    result["train_wall_seconds"] = sum(int(l) for l in open(secs) if l.strip())
json.dump(result, open(out, "w"), indent=2)
print(json.dumps({k: result[k]["all"] for k in ("simplenet", "stacknet")}, indent=1))
EOF
  if [[ -x "$FIGURES" ]]; then
    local rows=()
    for f in te08_000030 te08_000110 te09_000070 te10_000120; do
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
  all) step_data; step_train; step_export; step_eval ;;
  data) step_data ;;
  train) step_train ;;
  monitor) curve_monitor ;;  # the curve of a training started elsewhere
  export) step_export ;;
  eval) step_eval ;;
  *) echo "usage: $0 [all|data|train|monitor|export|eval]" >&2; exit 2 ;;
esac

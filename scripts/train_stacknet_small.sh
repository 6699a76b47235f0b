#!/usr/bin/env bash
# Reproduces models/stacknet_small.pt and its depth metrics: renders the
# simulated training / held-out sequences, trains configs/stacknet_cpu_small.yaml
# on the CPU, exports SimpleNet and StackNet, predicts on the held-out sequence
# and evaluates both with `dvso eval-depth` (0-80 m).
#
#   scripts/train_stacknet_small.sh [DVSO_BINARY]   (env: RUN=/tmp/sn_small_run)
# The data folder is the one configs/stacknet_cpu_small.yaml names (/tmp/dvso_stacknet_data). A rerun
# skips what is done: rendered worlds, a finished training (an interrupted one resumes).
set -euo pipefail
cd "$(dirname "$0")/.."
DVSO=${1:-build/dvso}
DATA=/tmp/dvso_stacknet_data
RUN=${RUN:-/tmp/sn_small_run}
mkdir -p "$DATA"
# name  KITTI pose file  world seed  (200 frames, every 2nd pose from pose 100, 640x192, colour)
for spec in "train_00 00 11" "train_02 02 12" "train_05 05 13" "test_08 08 14"; do
  set -- $spec
  [[ -f "$DATA/$1/disp_1/000199.png" ]] && continue
  "$DVSO" simulate --out "$DATA/$1" --trajectory "data/kitti_poses/$2.txt" --first 100 --count 200 --stride 2 \
    --seed "$3" --width 640 --height 192 --color --quiet
done
if [[ ! -f "$RUN/checkpoint_final.pt" ]]; then
  resume=()
  [[ -f "$RUN/checkpoint_last.pt" ]] && resume=(--resume)
  "$DVSO" train --config configs/stacknet_cpu_small.yaml --output-dir "$RUN" "${resume[@]}"
fi
"$DVSO" export --checkpoint "$RUN/checkpoint_stage2_simple_Ko_sup.pt" --model simple --out "$RUN/simplenet_small.pt"
"$DVSO" export --checkpoint "$RUN/checkpoint_final.pt" --model stack --out "$RUN/stacknet_small.pt"
for net in simplenet stacknet; do
  "$DVSO" predict --model "$RUN/${net}_small.pt" --sequence "$DATA/test_08" --out "$RUN/pred_$net" --no-color
  "$DVSO" predict --model "$RUN/${net}_small.pt" --sequence "$DATA/test_08" --out "$RUN/pred_${net}_pp" --no-color --post-process
  for variant in "$net" "${net}_pp"; do
    echo "== $variant"
    "$DVSO" eval-depth --pred "$RUN/pred_$variant/left" --gt "$DATA/test_08/disp_0" \
      --calib "$DATA/test_08/calib.txt" --max-depth 80 --json | tee "$RUN/metrics_$variant.json"
  done
done

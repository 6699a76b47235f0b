#!/usr/bin/env bash
# Turns what scripts/gpu/train_on_device.sh sent back into a model file: joins the weights-only checkpoint's 15 MiB
# parts (the device tool returns files of at most 16 MiB), checks them against the checksum computed on the device
# and exports StackNet with this machine's LibTorch (Debian 1.13: the file every build of `dvso` loads), with the
# training camera the device recorded.
#
#   scripts/gpu/collect_model.sh FILES_DIR [OUT_MODEL]    (env: DVSO=build/dvso; OUT_MODEL default:
#                                                           gpu_out/stacknet_gpu.pt, ignored by git)
#
# To ship it (docs/stacknet.md, "The GPU path"): the tb step (`dvso tune-baseline --model OUT_MODEL ...
# --write-model models/stacknet_cpu_main.pt`, as scripts/train_stacknet.sh tb does), `dvso bench` on 2 CPU threads
# and benchmarks/run_dvso.sh on the held-out worlds.
set -euo pipefail
DIR=${1:?usage: $0 FILES_DIR [OUT_MODEL]}
OUT_MODEL=${2:-$(dirname "$0")/../../gpu_out/stacknet_gpu.pt}  # FILES_DIR is read-only
DVSO=${DVSO:-build/dvso}
ls "$DIR"/weights_final.pt.part* > /dev/null 2>&1 || { echo "error: no weights_final.pt.part* in $DIR" >&2; exit 1; }
WEIGHTS=$(mktemp --suffix=.pt)
trap 'rm -f "$WEIGHTS"' EXIT
cat $(ls "$DIR"/weights_final.pt.part* | sort) > "$WEIGHTS"
[[ -f "$DIR/result.json" ]] || { echo "error: no result.json in $DIR" >&2; exit 1; }
read -r expected baseline fx_over_width complete < <(python3 -c "
import json, sys
r = json.load(open(sys.argv[1]))
print(r['weights_sha256'], r['model_metadata']['baseline'], r['model_metadata']['fx_over_width'], r['schedule_complete'])" \
  "$DIR/result.json")
actual=$(sha256sum "$WEIGHTS" | cut -d' ' -f1)
[[ "$expected" == "$actual" ]] || { echo "error: joined weights' sha256 $actual != $expected (sent)" >&2; exit 1; }
[[ $complete == True ]] || echo "warning: the device's schedule did not finish (time limit): the model is its last checkpoint" >&2
mkdir -p "$(dirname "$OUT_MODEL")"
# auto: StackNet when the schedule reached its StackNet stages, else SimpleNet.
"$DVSO" export --checkpoint "$WEIGHTS" --model auto --training-baseline "$baseline" \
  --training-fx-over-width "$fx_over_width" --out "$OUT_MODEL"
python3 -c "
import json, sys
r = json.load(open(sys.argv[1]))
m = r['metrics']
if m is None:
    print('no held-out metrics (the device evaluation failed or ran out of time: run_logs.tgz)')
else:
    # 'stacknet' holds the model as trained, a SimpleNet when the schedule ended before its StackNet stages.
    kind = r['model_metadata'].get('model_kind', 'stack')
    for net, name in (('simplenet', 'SimpleNet'), ('stacknet', 'StackNet' if kind == 'stack' else 'SimpleNet (as trained)')):
        a = m[net]['all']
        print(f\"{name} on the device: held-out abs rel {a['abs_rel']:.4f}, d<1.25 {a['a1']:.3f}\")" "$DIR/result.json"

#!/usr/bin/env bash
# GPU latency of StackNet: builds `dvso` against the CUDA LibTorch that ships
# inside a PyTorch pip install (Debian's libtorch-dev is CPU-only), exports the
# paper config (ResNet-50, 512x256) with random weights, and runs `dvso bench`
# for fp32 / fp16 / bf16.
#
#   scripts/bench_gpu.sh [MODEL.pt]     (env: PYTHON, BUILD_DIR, HEIGHT, WIDTH, BATCH, RUNS)
#
# Needs: python3 with a CUDA build of torch already installed (as on the lent device image; this project installs
# nothing from PyPI) (`python3 -c "import torch; print(torch.cuda.is_available())"`).
# The C++ ABI of the pip wheel decides _GLIBCXX_USE_CXX11_ABI; CMake picks it up
# from TorchConfig.cmake, the other dependencies are the Debian ones.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
BUILD_DIR=${BUILD_DIR:-build-gpu}
HEIGHT=${HEIGHT:-256}
WIDTH=${WIDTH:-512}
BATCH=${BATCH:-1}
RUNS=${RUNS:-100}

TORCH_CMAKE=$("$PYTHON" -c "import torch; print(torch.utils.cmake_prefix_path)")
"$PYTHON" -c "import torch; assert torch.cuda.is_available(), 'torch sees no CUDA device'; print('PyTorch', torch.__version__, 'CUDA', torch.version.cuda, torch.cuda.get_device_name(0))"
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release -DDVSO_WITH_TORCH=ON \
  -DDVSO_BUILD_TESTS=OFF -DDVSO_BUILD_BENCHMARKS=OFF -DCMAKE_PREFIX_PATH="$TORCH_CMAKE"
cmake --build "$BUILD_DIR" -j "$(nproc)" --target dvso
DVSO="$BUILD_DIR/dvso"  # pipelines/CMakeLists.txt puts the binary at the top of the build folder

MODEL=${1:-}
if [[ -z "$MODEL" ]]; then
  # Random-weight paper model: latency does not depend on the weights.
  WORK=$(mktemp -d)
  MODEL="$WORK/stacknet_paper.pt"
  "$DVSO" export --config configs/stacknet_paper.yaml --random-init --model stack --out "$MODEL"
  SIMPLE="$WORK/simplenet_paper.pt"
  "$DVSO" export --config configs/stacknet_paper.yaml --random-init --model simple --out "$SIMPLE"
  "$DVSO" bench --model "$SIMPLE" --device cuda --height "$HEIGHT" --width "$WIDTH" --batch "$BATCH" --runs "$RUNS" --json
fi
"$DVSO" bench --model "$MODEL" --device cuda --height "$HEIGHT" --width "$WIDTH" --batch "$BATCH" --runs "$RUNS" --json

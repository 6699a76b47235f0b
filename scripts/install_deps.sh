#!/usr/bin/env bash
# Installs every build and run-time dependency from Debian packages.
# Idempotent: does nothing when all packages are already present.
set -euo pipefail
PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libopencv-dev libyaml-cpp-dev libsuitesparse-dev libopenblas-dev
  libcli11-dev nlohmann-json3-dev libgtest-dev libgmock-dev libbenchmark-dev
  libtorch-dev
  time python3  # benchmarks/*.sh: peak memory (/usr/bin/time -f %M) and their JSON summaries
  python3-yaml  # scripts/gpu/stage_steps.py (the GPU training script's schedule) and its test
)
missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install_deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"

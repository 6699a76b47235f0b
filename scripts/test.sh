#!/usr/bin/env bash
# Installs dependencies, builds, and runs the whole test suite with CTest; then
# builds the non-Torch configuration with AddressSanitizer + UndefinedBehaviorSanitizer
# (no recovery: any finding fails its test) into ${SANITIZE_BUILD_DIR:-build-asan}
# and runs its test suite too. On 2 cores, from a fresh clone: ~50 min in all (README, test-suite row).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
ctest --test-dir "${BUILD_DIR:-build}" --output-on-failure -j "${JOBS:-$(nproc)}"

SANITIZE_BUILD_DIR=${SANITIZE_BUILD_DIR:-build-asan}
BUILD_DIR="$SANITIZE_BUILD_DIR" scripts/build.sh -DDVSO_SANITIZE=ON -DDVSO_WITH_TORCH=OFF -DDVSO_BUILD_BENCHMARKS=OFF
ctest --test-dir "$SANITIZE_BUILD_DIR" --output-on-failure -j "${JOBS:-$(nproc)}"

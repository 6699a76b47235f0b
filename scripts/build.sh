#!/usr/bin/env bash
# Configures and builds dvso (Release) into ${BUILD_DIR:-build}.
# Extra arguments go to CMake, e.g. scripts/build.sh -DDVSO_SANITIZE=ON. Every run starts from the
# project's option defaults (then applies the arguments), so an option given once does not stay in
# the build folder's cache and change what a later scripts/test.sh or scripts/demo.sh builds.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
DEFAULTS=(-DDVSO_SANITIZE=OFF -DDVSO_WITH_TORCH=ON -DDVSO_BUILD_TESTS=ON -DDVSO_BUILD_BENCHMARKS=ON -DDVSO_NATIVE=OFF)
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" "${DEFAULTS[@]}" "$@"
cmake --build "$BUILD_DIR" -j "$JOBS"

#!/usr/bin/env bash
# Installs dependencies, builds, and runs `dvso demo` on data the repo ships/generates.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
scripts/build.sh
"${BUILD_DIR:-build}/dvso" demo --out "${DEMO_OUT:-demo_out}"

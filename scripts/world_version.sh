# Simulator world versions (core/simulator.h's kSimulatorWorldVersion and its history), for scripts that cache
# rendered worlds: sourced by scripts/train_stacknet.sh and benchmarks/run_label_worlds.sh.

# The world version a simulation.yaml records: version 2 wrote only `reconcile_altitude: true`, version 1 neither
# key. Not told apart: worlds rendered by the transient commits 9d74e92-550d2c5 and a52f8fc-9dab4e5 of sessions
# 38-39 (read as 2 but with version 3's invented streets).
recorded_world_version() {  # simulation.yaml
  local version
  version=$(sed -n 's/^world_version: *\([0-9][0-9]*\).*/\1/p' "$1")
  if [[ -z $version ]]; then
    if grep -q '^reconcile_altitude: true' "$1"; then version=2; else version=1; fi
  fi
  echo "$version"
}

# The current world version of a dvso binary (`dvso --version`); an error for one built before session 39.
binary_world_version() {  # dvso
  local version
  version=$({ "$1" --version 2> /dev/null || true; } | sed -n 's/.*simulator world version \([0-9][0-9]*\).*/\1/p')
  [[ -n $version ]] || { echo "error: $1 --version names no simulator world version (built before session 39?)" >&2; return 1; }
  echo "$version"
}

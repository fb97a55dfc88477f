#!/usr/bin/env bash
# Runs every benchmark program of the build (targets named bench_*). Figures go in README.md.
# Usage: deploy/bench.sh [BUILD_DIR]
set -euo pipefail
build=${1:-build}
export CONCERT_DOMAIN_ID=${CONCERT_DOMAIN_ID:-199}
mapfile -t benches < <(find "$build" -type f -executable -name 'bench_*' | sort)
[ ${#benches[@]} -gt 0 ] || { echo "bench.sh: no bench_* programs under $build (run make build first)" >&2; exit 1; }
for b in "${benches[@]}"; do
  echo "=== $(basename "$b")"
  "$b"
  echo
done

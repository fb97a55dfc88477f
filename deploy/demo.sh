#!/usr/bin/env bash
# `make demo`: the plug-and-work pipeline in simulation, on this machine.
#   1. start the services that exist (discovery, modelgen; the robot service when built)
#   2. "assemble" the drill robot: its scan is published as the EtherCAT master would
#   3. discovery rebuilds the module tree, modelgen publishes robot model version 1
#   4. hot swap: the drill is replaced by the sanding tool -> new scan -> model version 2
# with the time of each stage. Logs stay in a temp folder (printed at the end).
# Usage: deploy/demo.sh [BUILD_DIR]    Domain: CONCERT_DOMAIN_ID (default 0).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
concert=$build/tools/concert/concert
discovery=$build/services/discovery/concert_discovery
modelgen=$build/services/modelgen/concert_modelgen
for b in "$concert" "$discovery" "$modelgen"; do
  [ -x "$b" ] || { echo "demo: $b is missing: run 'make build' first" >&2; exit 1; }
done
export CONCERT_DOMAIN_ID=${CONCERT_DOMAIN_ID:-0}
logs=$(mktemp -d /tmp/concert-demo.XXXXXX)
pids=()
t0=$(date +%s%N)

cleanup() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$p" 2>/dev/null || true
  done
  echo "demo: logs in $logs"
}
trap cleanup EXIT

ms_since() { echo $(( ($(date +%s%N) - $1) / 1000000 )); }
seconds() { printf '%d.%03d' $(( $1 / 1000 )) $(( $1 % 1000 )); }
stage() { printf '\n[%8s s] == %s\n' "$(seconds "$(ms_since "$t0")")" "$*"; }
start() {
  local name=$1; shift
  "$@" > "$logs/$name.log" 2>&1 &
  pids+=($!)
}
# Waits until the live model has the given version; prints it.
wait_model() {
  local version=$1
  for _ in $(seq 60); do
    if "$concert" model show --timeout 1 > "$logs/model.txt" 2>&1 && grep -q "version $version\b" "$logs/model.txt"; then
      sed -n '1,9p' "$logs/model.txt"
      grep -A20 '^end-effectors' "$logs/model.txt"
      return 0
    fi
    sleep 0.2
  done
  echo "demo: model version $version did not appear; service logs:" >&2
  tail -n 5 "$logs"/*.log >&2
  return 1
}

stage "domain $CONCERT_DOMAIN_ID: starting discovery and modelgen"
start discovery "$discovery"
start modelgen "$modelgen"

stage "assembling the drill robot (deploy/demo/drill_robot.yaml): its EtherCAT scan goes on the bus"
"$concert" scan show --assembly deploy/demo/drill_robot.yaml | head -4
echo "  ..."
start bus "$concert" scan publish --assembly deploy/demo/drill_robot.yaml --scan-id 1 --source demo-bus
bus_pid=${pids[-1]}

stage "discovery -> module tree -> modelgen -> robot model"
wait_model 1
stage "model version 1 is live"

stage "topics on the domain"
"$concert" topic list --wait-ms 1000

stage "hot swap: the drill is replaced by the sanding tool"
kill -INT "$bus_pid"
start bus2 "$concert" scan publish --assembly deploy/demo/sanding_robot.yaml --scan-id 2 --source demo-bus
swap=$(date +%s%N)
wait_model 2
stage "model version 2 is live, $(seconds "$(ms_since "$swap")") s after the new scan"

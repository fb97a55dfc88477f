#!/usr/bin/env bash
# bench_ethercat: the master against the virtual ring of the paper's 19-ESC robot over a veth pair
# between two network namespaces (made and removed here): bring-up time (`concert scan read`, 20
# times), then the robot's ring with its MuJoCo drives (--robot) cycled at 1 kHz for --seconds
# (default 60): period, jitter p99, frames lost, master CPU per cycle. Needs root.
# Usage: bench_ethercat [--seconds S] [--fifo PRIO]   (run from the build tree: make bench)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
build=$(cd "$here/../.." && pwd)
src=$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$build/CMakeCache.txt")
seconds=60
fifo=0
usage="Usage: bench_ethercat [--seconds S] [--fifo PRIO]
  --seconds S   how long the 1 kHz cycle runs (default 60)
  --fifo PRIO   run the master's cycle thread SCHED_FIFO at PRIO (default: SCHED_OTHER)
Needs root: two network namespaces and a veth pair are made and removed."
while [ $# -gt 0 ]; do
  case "$1" in
    -h|--help) echo "$usage"; exit 0 ;;
    --seconds|--fifo)
      [ $# -ge 2 ] || { echo "bench_ethercat: $1 needs a value" >&2; exit 2; }
      [[ "$2" =~ ^[0-9]+$ ]] && [ "$2" -ge 1 ] ||
        { echo "bench_ethercat: $1: '$2' is not a whole number >= 1" >&2; exit 2; }
      if [ "$1" = --seconds ]; then seconds=$2; else fifo=$2; fi
      shift 2 ;;
    *) echo "bench_ethercat: unknown argument '$1'" >&2; echo "$usage" >&2; exit 2 ;;
  esac
done
[ "$(id -u)" -eq 0 ] || { echo "bench_ethercat: needs root (network namespaces, raw sockets)" >&2; exit 1; }
ring_bin="$build/tools/ecat_ring/concert_ecat_ring"
concert="$build/tools/concert/concert"
db="$src/../shared/data/concert_resources"
tag=$$
ns_master="concert-bm-$tag"
ns_ring="concert-br-$tag"
work=$(mktemp -d)
ring_pid=""
cleanup() {
  [ -n "$ring_pid" ] && kill "$ring_pid" 2>/dev/null || true
  wait 2>/dev/null || true
  ip netns del "$ns_master" 2>/dev/null || true
  ip netns del "$ns_ring" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
ip netns add "$ns_master"
ip netns add "$ns_ring"
ip link add "bem$tag" type veth peer name "ber$tag"
ip link set "bem$tag" netns "$ns_master"
ip link set "ber$tag" netns "$ns_ring"
ip -n "$ns_master" link set "bem$tag" up
ip -n "$ns_ring" link set "ber$tag" up

start_ring() {
  ip netns exec "$ns_ring" "$ring_bin" --ifname "ber$tag" "$@" > "$work/ring.log" 2>&1 &
  ring_pid=$!
  for _ in $(seq 300); do grep -q "concert_ecat_ring: serving" "$work/ring.log" && return 0; sleep 0.1; done
  cat "$work/ring.log" >&2
  echo "bench_ethercat: the ring did not start" >&2
  exit 1
}
stop_ring() { kill -INT "$ring_pid"; wait "$ring_pid" || true; ring_pid=""; }

start_ring --assembly "$src/libs/simbus/examples/concert_paper_robot.yaml" --module-db "$db"
for i in $(seq 20); do
  ip netns exec "$ns_master" "$concert" scan read --ifname "bem$tag" 2>&1 >/dev/null |
    sed -n 's/.* in \([0-9.]*\) ms (\([0-9]*\) frames, \([0-9]*\) lost)/\1 \2 \3/p' >> "$work/bringup.txt"
done
stop_ring
python3 - "$work/bringup.txt" <<'PY'
import sys, statistics
rows = [tuple(float(x) for x in line.split()) for line in open(sys.argv[1]) if line.strip()]
ms = sorted(r[0] for r in rows)
print("bring-up of the paper robot's 19 ESCs (scan read: count, addresses, registers, DC times, SII): "
      "%d runs, median %.1f ms, max %.1f ms, %d frames each, %d lost in all" % (
      len(ms), statistics.median(ms), ms[-1], int(rows[0][1]), int(sum(r[2] for r in rows))))
PY
start_ring --assembly "$src/deploy/demo/drill_robot.yaml" --robot
args=(--ifname "bem$tag" --seconds "$seconds" --json --lost-in-a-row 0)
[ "$fifo" -gt 0 ] && args+=(--fifo "$fifo")
ip netns exec "$ns_master" "$concert" ethercat cycle "${args[@]}" > "$work/cycle.json"
stop_ring
python3 - "$work/cycle.json" "$seconds" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
print("1 kHz cycle, the demo robot's ring (19 ESCs, %d drive boards, its MuJoCo robot behind them), %s s, %s: "
      "%d cycles, period p50 %.1f us, p99 %.1f us, max %.1f us; jitter p99 %.1f us; %d frames lost, "
      "%d working counters short; master CPU %.1f us per cycle" % (
      c["process_data_slaves"], sys.argv[2], c["scheduling"], c["cycles"], c["period_p50_us"],
      c["period_p99_us"], c["period_max_us"], c["jitter_p99_us"], c["lost"], c["short_wkc"],
      c["cpu_per_cycle_us"]))
PY

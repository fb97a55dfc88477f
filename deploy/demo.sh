#!/usr/bin/env bash
# `make demo`: the plug-and-work pipeline in simulation, on this machine.
#   1. `concert up` starts every service that is built: the simulated robot (MuJoCo) with the
#      drill robot of deploy/demo/drill_robot.yaml mounted, discovery, modelgen, safety, ...
#   2. the robot's simulated EtherCAT bus publishes the scan; discovery rebuilds the module
#      tree; modelgen publishes robot model version 1; every service reconfigures to it
#   3. the main job: a drilling mission on the wall of deploy/demo/drill_site.yaml (two blue
#      blobs): the area is located from a picked point, the planner plans the whole-body
#      approach (NSPG goal posture + path, 200 N checked) in the map it builds from the robot's
#      lidars and depth cameras (`concert up --map sensors`), the robot executes it, the drill
#      service detects the blobs and drills the one nearest the point with Cartesian impedance
#      and visual servoing; the report, and the hole the simulator's wall records
#   4. hot swap: the drill is replaced by the sanding tool -> new scan -> tree -> model
#      version 2 -> every service ready again, with the time of each stage
# Usage: deploy/demo.sh [BUILD_DIR]    Domain: CONCERT_DOMAIN_ID (default 0). DEMO_KEEP=1: keep the stack
#        (and the operator GUI, whose address it prints) up after the demo, until Ctrl-C.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
concert=$build/tools/concert/concert
[ -x "$concert" ] || { echo "demo: $concert is missing: run 'make build' first" >&2; exit 1; }
export CONCERT_DOMAIN_ID=${CONCERT_DOMAIN_ID:-0}
log=$(mktemp /tmp/concert-demo.XXXXXX.log)
t0=$(date +%s%N)
ms_since() { echo $(( ($(date +%s%N) - $1) / 1000000 )); }
seconds() { printf '%d.%03d' $(( $1 / 1000 )) $(( $1 % 1000 )); }
stage() { printf '\n[%8s s] == %s\n' "$(seconds "$(ms_since "$t0")")" "$*"; }

up_pid=""
cleanup() {
  if [ -n "$up_pid" ] && kill -0 "$up_pid" 2>/dev/null; then
    kill -INT "$up_pid"
    for _ in $(seq 100); do kill -0 "$up_pid" 2>/dev/null || break; sleep 0.1; done
  fi
  echo "demo: launcher log $log; service logs in ${XDG_RUNTIME_DIR:-/tmp}/concert-d$CONCERT_DOMAIN_ID/logs"
}
trap cleanup EXIT

# The end state decides: safety RUNNING, every service ready at one model (version and hash),
# nothing stopped or in error, nothing refused. Anything else fails the demo, with the reason.
fail() {
  echo "demo: FAILED: $*" >&2
  exit 1
}
check_end_state() {
  local what=$1 safety
  safety=$("$concert" safety status --timeout 5) || fail "$what: no safety state ($safety)"
  echo "  $safety"
  case "$safety" in
    "safety: RUNNING"*) ;;
    *) fail "$what: the safety service stopped the robot: $safety" ;;
  esac
  "$concert" status --check --timeout 1.5 | sed 's/^/  /' ||
    fail "$what: a service is stopped or in error, disagrees on the model, or refused input (above)"
}

stage "concert up: every service on this machine, domain $CONCERT_DOMAIN_ID, drill robot mounted"
"$concert" up --assembly deploy/demo/drill_robot.yaml --world deploy/demo/drill_site.yaml --map sensors > "$log" 2>&1 &
up_pid=$!
sleep 0.5
sed 's/^/  /' "$log"

stage "scan -> module tree -> robot model v1 -> every service reconfigures"
"$concert" status --until-version 1 --timeout 60 | sed 's/^/  /'

stage "concert status"
"$concert" status --timeout 1 | sed 's/^/  /'

gui=$(grep -o 'operator GUI: http://[^ ]*' "$log" | head -1 || true)
stage "${gui:-operator GUI: not built (services/gui)}"
[ -n "$gui" ] && echo "  open it in a browser on this machine while the demo runs (DEMO_KEEP=1: the stack stays up at the end)"

stage "the live model"
"$concert" model show --timeout 5 | sed -n '1,8p;/^end-effectors/,$p' | sed 's/^/  /'

stage "sensors: what the robot carries, and the drill camera's next RGB-D frame"
"$concert" camera list --timeout 5 | sed 's/^/  /'
snapshots=$(mktemp -d /tmp/concert-demo-camera.XXXXXX)
"$concert" camera snapshot --camera camera_E --out "$snapshots" --timeout 10 | sed 's/^/  /' ||
  fail "no frame from the drill camera"
"$concert" topic hz concert/sensors/imu --timeout 3 | sed 's/^/  /' || true

stage "drilling mission: concert drill run --mission deploy/demo/drill_mission.yaml (blobs on the wall 2.2 m ahead)"
"$concert" drill run --mission deploy/demo/drill_mission.yaml --timeout 300 | sed 's/^/  /' ||
  fail "the drilling mission failed (report above)"
holes=$("$concert" topic echo concert/sim/holes --count 1 --timeout 5 --json) || fail "no hole in the simulator's wall"
echo "  the simulator's wall: $(echo "$holes" | grep -o '"wall"' | wc -l) holes cut"
# The map the planner planned in: built from the robot's lidars and depth cameras.
run_dir=$(grep -o 'run folder [^ ]*' "$log" | head -1 | cut -d' ' -f3)
map_line=$(grep 'planner: sensor map: used' "$run_dir/logs/planner.log" 2>/dev/null | tail -1 | cut -c1-200 || true)
[ -n "$map_line" ] || fail "the planner built no map from the sensors ($run_dir/logs/planner.log)"
echo "  the planner's map: ${map_line#planner: sensor map: }"

stage "after the drilling mission: safety RUNNING, one model everywhere, nothing refused"
check_end_state "after the drilling mission"

stage "hot swap: concert sim swap deploy/demo/sanding_robot.yaml (drill -> sanding tool)"
swap=$(date +%s%N)
"$concert" sim swap deploy/demo/sanding_robot.yaml | sed 's/^/  /'
"$concert" status --until-version 2 --timeout 60 | sed 's/^/  /'
stage "model version 2 live in every service (stage times above count from the swap)"
"$concert" status --timeout 1 | sed 's/^/  /'
"$concert" model show --timeout 5 | sed -n '/^end-effectors/,$p' | sed 's/^/  /'

stage "spraying (services/surface_finish): a 0.4 m x 0.4 m area in MuJoCo, coverage from the true TCP"
spray_bench=$build/services/surface_finish/bench_surface_finish
if [ -x "$spray_bench" ]; then
  "$spray_bench" --short --out "${XDG_RUNTIME_DIR:-/tmp}/concert-d$CONCERT_DOMAIN_ID/spray" | sed 's/^/  /' ||
    fail "the spraying run missed its aims (coverage >= 99 %, |dh| <= 5 mm, coats 100 +- 5 mm)"
else
  echo "  (not built: $spray_bench)"
fi

stage "topics on the domain"
"$concert" topic list --timeout 1 | sed 's/^/  /'

stage "end state: safety RUNNING, every service ready at model version 2, nothing refused"
check_end_state "at the end"
# The simulated robot never runs a cycle late in simulated time; a loaded machine slows
# simulated time instead, and the robot's log says by how much every 10 s.
timing=$(grep -h "simulated time at" "${XDG_RUNTIME_DIR:-/tmp}/concert-d$CONCERT_DOMAIN_ID/logs/robot.log" | tail -1 || true)
[ -n "$timing" ] || fail "the robot's log says nothing of its simulated time"
echo "  robot: ${timing#concert_robot: }"
echo "demo: OK"
if [ "${DEMO_KEEP:-0}" = 1 ] && [ -n "$gui" ]; then
  echo "demo: the stack stays up (${gui}); Ctrl-C stops it"
  wait "$up_pid" || true
fi

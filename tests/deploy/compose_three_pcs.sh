#!/usr/bin/env bash
# The deployment for real: the robot's three onboard PCs as three network namespaces on one
# bridge (rt-pc 10.10.0.1, nav-pc 10.10.0.2, manip-pc 10.10.0.3: the peers of
# deploy/dds/fastdds_profiles.xml), each running its compose profile of deploy/compose.yaml
# with the image of `make image`, through a podman API service started inside its namespace
# (so that the containers' host networking is that namespace), with DDS Security on: each PC
# mounts only its own identities. A fourth namespace (10.10.0.9) is the crew's laptop: it runs
# the build tree's `concert` as the operator.
#
# Checks, in order:
#   1. every service of the three PCs ready at one model version and hash, each with its PC's
#      CONCERT_HOST, safety RUNNING (`concert status --check`);
#   2. a participant without a certificate sees no service and its e-stop changes nothing;
#   3. a drilling approach planned on manip-pc and executed by the robot on rt-pc;
#   4. a hot swap (concert sim swap): every container ready at the new model;
#   5. the planner's process killed: its restart policy restarts the container, ready at the
#      current model; the safety service stopped the robot naming it; reset -> RUNNING;
#   6. nav-pc's link cut: the safety service stops the robot naming nav; link back, reset ->
#      RUNNING, every service ready again.
# Containers, volumes, namespaces and the podman services it started are removed at the end,
# also when it fails (the image stays). Exit 77 (ctest: skipped) only when not run as root.
#
# Usage: tests/deploy/compose_three_pcs.sh [BUILD_DIR]
# Environment: CONCERT_IMAGE (default concert/stack:latest), COMPOSE_TEST_KEEP_LOGS=DIR (copy
# every container's log there).
set -euo pipefail

src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=$(cd "${1:-$src/build}" && pwd)
concert="$build/tools/concert/concert"
image=${CONCERT_IMAGE:-concert/stack:latest}
compose_file="$src/deploy/compose.yaml"
t0=$(date +%s)

log() { echo "compose-test: [$(( $(date +%s) - t0 )) s] $*"; }
fail() { echo "compose-test: FAILED after $(( $(date +%s) - t0 )) s: $*" >&2; exit 1; }

if [ "$(id -u)" -ne 0 ]; then
  echo "compose-test: SKIPPED: needs root (network namespaces, podman as root)"
  exit 77
fi
for tool in podman docker-compose ip nsenter python3 curl; do
  command -v "$tool" >/dev/null || fail "$tool is not installed (deploy/install-deps.sh installs it)"
done
[ -x "$concert" ] || fail "$concert is not built (make build)"
export CONTAINERS_CONF="$src/deploy/podman/containers.conf"

# ---- names: fixed, so that a run killed before its cleanup is cleaned by the next one ----
pcs=(rt nav manip)
declare -A address=([rt]=10.10.0.1 [nav]=10.10.0.2 [manip]=10.10.0.3 [obs]=10.10.0.9)
declare -A host_of=([rt]=rt-pc [nav]=nav-pc [manip]=manip-pc)
declare -A identities=([rt]="robot safety discovery modelgen" [nav]="nav operator" \
                       [manip]="planner drill collab surface_finish")
declare -A services_of=([rt]="robot safety discovery modelgen" [nav]="nav gui" \
                        [manip]="planner drill collab surface_finish")
ns_prefix=concert-ct
switch_ns=$ns_prefix-sw
project() { echo "concert-ct-$1"; }
ns() { echo "$ns_prefix-$1"; }
veth() { echo "cct-$1"; }

work=$(mktemp -d /tmp/concert-compose-test.XXXXXX)
declare -A engine_pid=()

compose() {  # compose PC ARGS...: docker-compose for PC's profile through PC's podman service
  local pc=$1; shift
  DOCKER_HOST="unix://$work/$pc.sock" CONCERT_PKI="$work/pki-$pc" \
    timeout 300 docker-compose -p "$(project "$pc")" -f "$compose_file" --profile "$pc" "$@"
}

remove_everything() {
  local pc c
  for pc in "${pcs[@]}"; do
    if [ -S "$work/$pc.sock" ]; then compose "$pc" down -v --timeout 5 >/dev/null 2>&1 || true; fi
  done
  for pc in "${pcs[@]}"; do
    for c in $(podman ps -a -q --filter "label=com.docker.compose.project=$(project "$pc")" 2>/dev/null); do
      podman rm -f "$c" >/dev/null 2>&1
    done
    for c in $(podman volume ls -q --filter "label=com.docker.compose.project=$(project "$pc")" 2>/dev/null); do
      podman volume rm -f "$c" >/dev/null 2>&1
    done
  done
  for pc in "${!engine_pid[@]}"; do
    kill "${engine_pid[$pc]}" 2>/dev/null && wait "${engine_pid[$pc]}" 2>/dev/null || true
  done
  for pc in "${pcs[@]}" obs sw; do
    ip netns del "$(ns "$pc")" 2>/dev/null || true
  done
  return 0
}

dump_logs() {
  local pc s
  for pc in "${pcs[@]}"; do
    for s in ${services_of[$pc]}; do
      local c; c="$(project "$pc")_${s}_1"
      podman container exists "$c" 2>/dev/null || continue
      echo "---- $c ($(podman inspect "$c" --format '{{.State.Status}}, restarted {{.RestartCount}} times' 2>/dev/null)) ----"
      podman logs --tail 25 "$c" 2>&1 | sed 's/^/  /'
      if [ -n "${COMPOSE_TEST_KEEP_LOGS:-}" ]; then
        mkdir -p "$COMPOSE_TEST_KEEP_LOGS" && podman logs "$c" > "$COMPOSE_TEST_KEEP_LOGS/$c.log" 2>&1
      fi
    done
  done
}

cleanup() {
  local rc=$?
  set +e
  trap - EXIT INT TERM
  if [ "$rc" -ne 0 ] && [ "$rc" -ne 77 ]; then
    echo "compose-test: the containers' last log lines:" >&2
    dump_logs >&2
  elif [ -n "${COMPOSE_TEST_KEEP_LOGS:-}" ]; then
    dump_logs >/dev/null
  fi
  log "removing containers, volumes, podman services and namespaces"
  remove_everything
  rm -rf "$work"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM
# A command failing outside the checks' own messages still says which one.
set -E
trap 'echo "compose-test: line $LINENO: failed: $BASH_COMMAND" >&2' ERR

set +e; remove_everything; set -e  # what a run killed before its cleanup left

# ---- the image: the one `make image` made of this build tree ----
podman image exists "$image" || fail "no image $image: run make image (deploy/image/build.sh)"
if ! diff <(podman run --rm --network none --entrypoint cat "$image" /opt/concert/manifest.sha256) \
          <("$src/deploy/image/manifest.sh" "$build") > "$work/manifest.diff"; then
  fail "the image $image is not made of this build and source tree ($(grep -c '^>' "$work/manifest.diff") files differ, e.g. $(grep -m1 '^>' "$work/manifest.diff" | awk '{print $3}')): run make image"
fi

# ---- the PKI: one CA, each PC gets only its identities (never the CA's key) ----
"$concert" security init "$work/pki" > /dev/null || fail "concert security init"
"$concert" security https "$work/pki" --name "${address[nav]}" --name nav-pc > /dev/null || fail "concert security https"
for pc in "${pcs[@]}"; do
  mkdir -p "$work/pki-$pc"
  cp "$work/pki/ca.pem" "$work/pki/governance.p7s" "$work/pki-$pc/"
  for id in ${identities[$pc]}; do cp -r "$work/pki/$id" "$work/pki-$pc/"; done
done
mkdir -p "$work/gui"
cp "$work/pki/gui/https_cert.pem" "$work/pki/gui/https_key.pem" "$work/gui/"
echo "compose-test-password" | "$concert" gui users add crew --role operator --users "$work/gui/users.json" > /dev/null \
  || fail "concert gui users add"

# ---- the network: a switch namespace with a bridge, one namespace per PC and the laptop ----
ip netns add "$switch_ns"
ip -n "$switch_ns" link add br0 type bridge
ip -n "$switch_ns" link set br0 up
for pc in "${pcs[@]}" obs; do
  ip netns add "$(ns "$pc")"
  ip link add "$(veth "$pc")" type veth peer name eth0 netns "$(ns "$pc")"
  ip link set "$(veth "$pc")" netns "$switch_ns"
  ip -n "$switch_ns" link set "$(veth "$pc")" master br0 up
  ip -n "$(ns "$pc")" addr add "${address[$pc]}/24" dev eth0
  ip -n "$(ns "$pc")" link set eth0 up
  ip -n "$(ns "$pc")" link set lo up
done
log "namespaces: ${pcs[*]} and the laptop (obs) on one bridge"

# ---- one podman API service inside each PC's namespace (nsenter: the network only, so that
# the cgroup and storage mounts stay the host's) ----
for pc in "${pcs[@]}"; do
  nsenter --net="/run/netns/$(ns "$pc")" podman system service --time=0 "unix://$work/$pc.sock" \
    > "$work/engine-$pc.log" 2>&1 &
  engine_pid[$pc]=$!
done
for pc in "${pcs[@]}"; do
  for _ in $(seq 100); do [ -S "$work/$pc.sock" ] && break; sleep 0.1; done
  [ -S "$work/$pc.sock" ] || fail "podman's API service of $pc did not start: $(tail -3 "$work/engine-$pc.log")"
done

# The limits of this machine: the robot's real-time limits may not exceed the hard ones.
export CONCERT_IMAGE="$image" CONCERT_DOMAIN_ID=0 CONCERT_GUI="$work/gui"
CONCERT_RTPRIO=$(ulimit -Hr); [ "$CONCERT_RTPRIO" = unlimited ] && CONCERT_RTPRIO=99
CONCERT_MEMLOCK=$(ulimit -Hl); [ "$CONCERT_MEMLOCK" = unlimited ] && CONCERT_MEMLOCK=-1 || CONCERT_MEMLOCK=$(( CONCERT_MEMLOCK * 1024 ))
export CONCERT_RTPRIO CONCERT_MEMLOCK

laptop() {  # the crew's laptop: the build tree's concert as the operator
  nsenter --net="/run/netns/$(ns obs)" env CONCERT_DOMAIN_ID=0 \
    CONCERT_DDS_PROFILES="$src/deploy/dds/fastdds_profiles.xml" CONCERT_SECURITY="$work/pki" "$concert" "$@"
}
stranger() {  # a participant on the bridge without a certificate
  nsenter --net="/run/netns/$(ns obs)" env -u CONCERT_SECURITY CONCERT_DOMAIN_ID=0 \
    CONCERT_DDS_PROFILES="$src/deploy/dds/fastdds_profiles.xml" "$concert" "$@"
}

# Every expected service heard, ready, on its PC, at one model version >= $1 and one hash.
check_everyone() {
  local want=$1 json
  json=$(laptop status --json --timeout 3) || return 1
  python3 - "$want" "$json" <<'EOF'
import json, sys
want = int(sys.argv[1]); rows = json.loads(sys.argv[2])
# The GUI gateway publishes no status of its own: its check is the HTTPS answer below.
expected = {"robot": "rt-pc", "safety": "rt-pc", "discovery": "rt-pc", "modelgen": "rt-pc",
            "nav": "nav-pc", "planner": "manip-pc", "drill": "manip-pc",
            "collab": "manip-pc", "surface_finish": "manip-pc"}
seen = {r["service"]: r for r in rows}
problems = []
for service, host in expected.items():
    r = seen.get(service)
    if r is None:
        problems.append(f"{service}: not heard"); continue
    if r["host"] != host: problems.append(f"{service}: on {r['host']}, expected {host}")
    if r["state"] != "ready": problems.append(f"{service}: {r['state']} ({r['message']})")
    if r["refusals"]: problems.append(f"{service}: {r['refusals']} refusals ({r['message']})")
models = {(r["model_version"], r["model_hash"]) for r in rows if r["model_version"] > 0}
if len(models) != 1: problems.append(f"models disagree: {sorted(models)}")
elif next(iter(models))[0] < want: problems.append(f"model version {next(iter(models))[0]} < {want}")
if problems:
    print("; ".join(problems)); sys.exit(1)
print(f"{len(seen)} services on 3 PCs, model version {next(iter(models))[0]} ({next(iter(models))[1][:12]})")
EOF
}
wait_everyone() {  # wait_everyone VERSION BOUND_S
  local deadline=$(( $(date +%s) + $2 )) out=""
  while [ "$(date +%s)" -lt "$deadline" ]; do
    if out=$(check_everyone "$1"); then echo "$out"; return 0; fi
  done
  echo "$out"
  return 1
}
# The safety state on one line: "RUNNING", or "STOPPED: cause; cause".
safety_state() {
  { laptop safety status --json --timeout 5 2>/dev/null || true; } | python3 -c '
import json, sys
try: s = json.loads(sys.stdin.read())
except ValueError: print("not heard"); sys.exit(0)
print(s["mode"] + (": " + "; ".join(s["causes"]) if s["causes"] else ""))'
}
wait_safety() {  # wait_safety REGEX BOUND_S
  local deadline=$(( $(date +%s) + $2 )) state=""
  while [ "$(date +%s)" -lt "$deadline" ]; do
    state=$(safety_state)
    if [[ "$state" =~ $1 ]]; then echo "$state"; return 0; fi
    sleep 0.5
  done
  echo "$state"
  return 1
}

# ---- 1. up: every PC its profile ----
up_start=$(date +%s)
for pc in "${pcs[@]}"; do
  compose "$pc" up -d > "$work/up-$pc.log" 2>&1 || fail "compose up of $pc: $(tail -5 "$work/up-$pc.log")"
done
log "compose up of rt, nav, manip done"
out=$(wait_everyone 1 240) || fail "not every service ready at one model within 240 s of compose up: $out"
log "1. ready $(( $(date +%s) - up_start )) s after compose up: $out"
state=$(wait_safety '^RUNNING' 30) || fail "safety not RUNNING: $state"
laptop status --check --timeout 5 > "$work/status.txt" 2>&1 || fail "concert status --check: $(cat "$work/status.txt")"
sed 's/^/  /' "$work/status.txt"
# The tablet's view: the GUI gateway on nav-pc answers HTTPS with the app, its certificate
# signed by the PKI's CA for nav-pc's address.
gui_url="https://${address[nav]}:8443/"
code=""
for _ in $(seq 60); do
  code=$(nsenter --net="/run/netns/$(ns obs)" curl -s -m 5 --cacert "$work/pki/ca.pem" -o "$work/gui.html" \
           -w '%{http_code}' "$gui_url" 2>/dev/null || true)
  [ "$code" = 200 ] && break
  sleep 0.5
done
[ "$code" = 200 ] && grep -qi '<html' "$work/gui.html" || fail "the GUI gateway at $gui_url: HTTP ${code:-no answer}"
log "   GUI gateway on nav-pc: $gui_url answers 200 with the app over TLS (the PKI's CA)"

# ---- 2. a participant without a certificate ----
stranger_out=$(stranger status --json --timeout 3 2>&1 || true)
python3 -c 'import json,sys; rows=json.loads(sys.argv[1]); sys.exit(1 if rows else 0)' "$stranger_out" 2>/dev/null \
  || fail "a participant without a certificate heard services: $stranger_out"
# The verb writes its e-stop and waits 3 s for the STOPPED state that answers it.
stranger safety estop --timeout 3 > "$work/stranger-estop.txt" 2>&1 || true
state=$(wait_safety '^(RUNNING|STOPPED)' 30) || fail "no safety state heard: $state"
[[ "$state" =~ ^RUNNING ]] || fail "an e-stop without a certificate changed the safety state: $state"
log "2. without a certificate: no service heard, its e-stop ignored (safety: $state)"

# ---- 3. a drilling approach planned on manip-pc, executed on rt-pc ----
laptop plan drill --at 2.0 0.0 1.2 --normal -1 0 0 --execute --timeout 180 > "$work/approach.txt" 2>&1 \
  || fail "the drilling approach: $(tail -5 "$work/approach.txt")"
log "3. drilling approach: $(tail -1 "$work/approach.txt")"

# ---- 4. hot swap (the arm home first, as the crew does) ----
laptop plan home --timeout 120 > "$work/home.txt" 2>&1 || fail "concert plan home: $(tail -5 "$work/home.txt")"
swap_start=$(date +%s)
laptop sim swap "$src/deploy/demo/sanding_robot.yaml" --timeout 30 > "$work/swap.txt" 2>&1 \
  || fail "concert sim swap: $(tail -3 "$work/swap.txt")"
out=$(wait_everyone 2 180) || fail "after the hot swap, not every service ready at model version 2: $out"
log "4. hot swap: $out, $(( $(date +%s) - swap_start )) s after the swap"

# ---- 5. the planner's process killed: restarted by its container's restart policy ----
planner_c="$(project manip)_planner_1"
init_pid=$(podman inspect "$planner_c" --format '{{.State.Pid}}')
planner_pid=$(pgrep -P "$init_pid" concert_planner) || fail "no concert_planner under $planner_c's init"
restarts_before=$(podman inspect "$planner_c" --format '{{.RestartCount}}')
kill_start=$(date +%s%N)
kill -KILL "$planner_pid"
for _ in $(seq 300); do
  [ "$(podman inspect "$planner_c" --format '{{.RestartCount}}')" -gt "$restarts_before" ] && break
  sleep 0.1
done
[ "$(podman inspect "$planner_c" --format '{{.RestartCount}}')" -gt "$restarts_before" ] \
  || fail "the planner's container was not restarted within 30 s of its process's SIGKILL"
restart_ms=$(( ($(date +%s%N) - kill_start) / 1000000 ))
out=$(wait_everyone 2 120) || fail "the restarted planner not ready at the current model: $out"
ready_ms=$(( ($(date +%s%N) - kill_start) / 1000000 ))
# A planner silent past the safety service's liveliness bound (1 s) stops the robot: then the
# stop must name it, and a reset must clear it.
stopped=$(wait_safety '^(RUNNING|STOPPED)' 30) || fail "no safety state heard after the planner's restart: $stopped"
if [[ "$stopped" =~ ^STOPPED ]]; then
  [[ "$stopped" =~ planner ]] || fail "the planner was killed, but the safety stop names something else: $stopped"
  laptop safety reset --timeout 10 > /dev/null 2>&1 || true
  state=$(wait_safety '^RUNNING' 30) || fail "no RUNNING after the reset: $state"
  stopped="safety stopped ($stopped), reset -> $state"
fi
log "5. planner killed: container restarted ${restart_ms} ms after the kill, every service ready at the current model after ${ready_ms} ms; $stopped"

# ---- 6. nav-pc's link cut ----
ip -n "$switch_ns" link set "$(veth nav)" down
state=$(wait_safety 'STOPPED.*nav' 20) || fail "nav-pc cut off: the safety service did not stop naming nav: $state"
log "6. nav-pc cut off: $state"
ip -n "$switch_ns" link set "$(veth nav)" up
out=$(wait_everyone 2 120) || fail "nav-pc back: not every service ready: $out"
laptop safety reset --timeout 10 > /dev/null 2>&1 || true
state=$(wait_safety '^RUNNING' 30) || fail "nav-pc back: no RUNNING after the reset: $state"
log "   link back, reset: $state; $out"
laptop status --check --timeout 5 > "$work/status.txt" 2>&1 || fail "concert status --check at the end: $(cat "$work/status.txt")"

log "PASSED"

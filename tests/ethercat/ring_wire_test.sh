#!/usr/bin/env bash
# The EtherCAT master on a wire. concert_ecat_ring serves an assembly's ring on one end of a veth
# pair; `concert scan read` reads it from the other end; each end is in a network namespace this
# test makes and removes. Every example assembly of libs/simbus must read, field for field, as
# `concert scan show --assembly` computes it (for concert_robot_18slaves.yaml: the real scan).
# One bring-up (the paper's 19-ESC robot) and one second of its cyclic process data are captured with tshark and decoded by Wireshark's
# EtherCAT dissector: no malformed frame but the one the test sends on purpose, and the commands
# a bring-up must send are there with the working counters the ring must return. Faults (a cable
# pulled, a board refusing OP, a module added) are named. Last, the robot service runs on the
# ring (--backend ethercat) and is ready at the model discovery and modelgen made from its scan.
# Usage: ring_wire_test.sh BUILD_DIR. Exit 77 (skipped) when not root.
set -euo pipefail

build=$(cd "$1" && pwd)
src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
db="$src/../shared/data/concert_resources"
examples="$src/libs/simbus/examples"
ring_bin="$build/tools/ecat_ring/concert_ecat_ring"
concert="$build/tools/concert/concert"

if [ "$(id -u)" -ne 0 ]; then
  echo "skipped: needs root (network namespaces and raw sockets)"
  exit 77
fi
for tool in ip tshark python3; do
  command -v "$tool" >/dev/null || { echo "FAIL: $tool is missing (deploy/install-deps.sh installs it)"; exit 1; }
done

# Leftovers of a run killed before its cleanup (ctest's timeout sends SIGKILL): namespaces
# named after a pid that no longer runs.
for ns in $(ip netns list | awk '{print $1}' | grep -E '^concert-ec[mr]-[0-9]+$' || true); do
  pid=${ns##*-}
  kill -0 "$pid" 2>/dev/null || ip netns del "$ns" 2>/dev/null || true
done
tag=$$
ns_master="concert-ecm-$tag"
ns_ring="concert-ecr-$tag"
work=$(mktemp -d)
ring_pid=""
tshark_pid=""
service_pids=()
cleanup() {
  [ -n "$ring_pid" ] && kill "$ring_pid" 2>/dev/null || true
  for pid in "${service_pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  [ -n "$tshark_pid" ] && kill "$tshark_pid" 2>/dev/null || true
  wait 2>/dev/null || true
  ip netns del "$ns_master" 2>/dev/null || true
  ip netns del "$ns_ring" 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

fail() { echo "FAIL: $*"; [ -f "$work/ring.log" ] && sed 's/^/  ring: /' "$work/ring.log"; exit 1; }

ip netns add "$ns_master"
ip netns add "$ns_ring"
ip link add "ecm$tag" type veth peer name "ecr$tag"
ip link set "ecm$tag" netns "$ns_master"
ip link set "ecr$tag" netns "$ns_ring"
ip -n "$ns_master" link set "ecm$tag" up
ip -n "$ns_ring" link set "ecr$tag" up

# Waits (bounded: 10 s) until FILE has a line matching PATTERN.
wait_for_line() {
  local file=$1 pattern=$2
  for _ in $(seq 100); do
    grep -q "$pattern" "$file" 2>/dev/null && return 0
    sleep 0.1
  done
  return 1
}

start_ring() {
  local file=$1
  shift
  : > "$work/ring.log"  # before the launch, so no line of an earlier ring is waited for
  ip netns exec "$ns_ring" "$ring_bin" --assembly "$file" --ifname "ecr$tag" --module-db "$db" "$@" \
    > "$work/ring.log" 2>&1 &
  ring_pid=$!
  wait_for_line "$work/ring.log" "concert_ecat_ring: serving" || fail "the ring did not start on $1"
}

stop_ring() {
  kill -INT "$ring_pid"
  # Bounded: 10 s for the ring to stop, then it is killed (and the test fails).
  for _ in $(seq 100); do kill -0 "$ring_pid" 2>/dev/null || break; sleep 0.1; done
  kill -0 "$ring_pid" 2>/dev/null && { kill -9 "$ring_pid"; fail "concert_ecat_ring did not stop on SIGINT"; }
  local rc=0
  wait "$ring_pid" || rc=$?
  ring_pid=""
  [ "$rc" -eq 0 ] || fail "concert_ecat_ring exited $rc after SIGINT"
  grep -q "concert_ecat_ring: stopped after [1-9][0-9]* frames" "$work/ring.log" ||
    fail "concert_ecat_ring did not report its frames on stopping"
}

# 1. Every example assembly: the master's scan is the simulated bus's.
for file in "$examples"/*.yaml; do
  name=$(basename "$file")
  start_ring "$file"
  ip netns exec "$ns_master" timeout 120 "$concert" scan read --frame-timeout 200 --tries 10 --ifname "ecm$tag" --json \
    > "$work/read.json" 2> "$work/read.err" || { cat "$work/read.err"; fail "scan read failed on $name"; }
  "$concert" scan show --assembly "$file" --module-db "$db" --json > "$work/show.json"
  cmp -s "$work/read.json" "$work/show.json" ||
    { diff "$work/show.json" "$work/read.json" | head -20; fail "$name: scan read differs from scan show"; }
  stop_ring
  echo "ok: $name: $(sed 's/concert scan read: //' "$work/read.err")"
done
# The 18-slave example is the real robot's: its scan read on the wire is the real scan.
real="$src/../shared/data/ethercat/concert_robot_18slaves.yaml"
start_ring "$examples/concert_robot_18slaves.yaml"
ip netns exec "$ns_master" timeout 120 "$concert" scan read --frame-timeout 200 --tries 10 --ifname "ecm$tag" --json > "$work/read.json" 2>/dev/null
stop_ring
"$concert" scan show --scan "$real" --json > "$work/real.json"
cmp -s "$work/read.json" "$work/real.json" ||
  { diff "$work/real.json" "$work/read.json" | head -20; fail "the 18-slave ring does not read as the real scan"; }
echo "ok: the 18-slave ring reads as ../shared/data/ethercat/concert_robot_18slaves.yaml"

# 2. A captured bring-up, decoded by Wireshark.
start_ring "$examples/concert_paper_robot.yaml"
ip netns exec "$ns_ring" tshark -i "ecr$tag" -B 32 -w "$work/bringup.pcapng" > "$work/tshark.log" 2>&1 &
tshark_pid=$!
wait_for_line "$work/tshark.log" "Capturing on" || fail "tshark did not start capturing"
ip netns exec "$ns_master" timeout 120 "$concert" scan read --frame-timeout 200 --tries 10 --ifname "ecm$tag" > /dev/null 2> "$work/read.err" ||
  { cat "$work/read.err"; fail "scan read failed during the capture"; }
# One frame that is not a valid EtherCAT frame (an FPRD whose 2047 bytes of data run past the
# frame): the ring must drop it and keep answering, and Wireshark must call it malformed (so the
# check below can fail).
ip netns exec "$ns_master" python3 - "ecm$tag" <<'PY'
import socket, sys
s = socket.socket(socket.AF_PACKET, socket.SOCK_RAW)
s.bind((sys.argv[1], 0))
header = b"\xff" * 6 + b"\x02\x00\x00\x00\x00\x09" + b"\x88\xa4" + b"\x20\x10"
fprd = b"\x04\x00\x01\x10\x10\x01\xff\x07"
s.send(header + fprd + b"\x00" * 36)
PY
wait_for_line "$work/ring.log" "dropped frame 1 that is not EtherCAT" || fail "the ring did not report the malformed frame"
# The ring to OP and one second of cyclic process data (one LRW a millisecond).
# (Lost frames are counted, not a reason to stop: a busy machine may delay the ring's process.)
ip netns exec "$ns_master" timeout 120 "$concert" ethercat cycle --frame-timeout 200 --tries 10 --ifname "ecm$tag" --seconds 1 --json --lost-in-a-row 0 \
  > "$work/cycle.json" 2> "$work/cycle.err" || { cat "$work/cycle.err"; fail "the ring stopped answering after a malformed frame"; }
kill -INT "$tshark_pid"
wait "$tshark_pid" || true
tshark_pid=""
stop_ring
malformed=$(tshark -r "$work/bringup.pcapng" -Y "_ws.malformed" 2>/dev/null | wc -l)
[ "$malformed" -eq 1 ] || fail "Wireshark finds $malformed malformed frames in the capture (expected the 1 sent on purpose)"
tshark -r "$work/bringup.pcapng" -Y "ecat && !_ws.malformed" -T fields -E separator=';' \
  -e ecat.cmd -e ecat.adp -e ecat.ado -e ecat.cnt 2>/dev/null > "$work/datagrams.txt"
python3 - "$work/datagrams.txt" 19 "$work/cycle.json" <<'PY' || fail "the capture lacks a command of the bring-up or the cycle"
import json, sys
n = int(sys.argv[2])
cycle = json.load(open(sys.argv[3]))
print("cycle: %d cycles, %d lost, %d short, expected working counter %d" % (
    cycle["cycles"], cycle["lost"], cycle["short_wkc"], cycle["expected_wkc"]))
datagrams = []
for line in open(sys.argv[1]):
    cmd, adp, ado, cnt = (field.split(",") for field in line.rstrip("\n").split(";"))
    # Logical commands (LRW) have a logical address instead of ADP/ADO: those fields are empty.
    if adp == [""]:
        adp = ado = ["-1"] * len(cmd)
    datagrams += [(int(c, 16), int(p, 16), int(o, 16), int(w)) for c, p, o, w in zip(cmd, adp, ado, cnt)]
BRD, APWR, FPRD, LRW = 7, 2, 4, 12
checks = {
    "BRD 0x0000 counting %d slaves" % n: any(c == BRD and o == 0 and w == n for c, p, o, w in datagrams),
    "APWR 0x0010 to every position": {p for c, p, o, w in datagrams if c == APWR and o == 0x10 and w == 0}
        == {(-i) & 0xFFFF for i in range(n)},
    "APWR 0x0010 taken by every slave": sum(1 for c, p, o, w in datagrams if c == APWR and o == 0x10 and w == 1) >= n,
    "FPRD 0x0110 answered by every station": {p for c, p, o, w in datagrams if c == FPRD and o == 0x110 and w == 1}
        == {0x1001 + i for i in range(n)},
    "SII reads (FPRD 0x0508)": any(c == FPRD and o == 0x508 and w == 1 for c, p, o, w in datagrams),
    "1000 cycles run": cycle["cycles"] == 1000,
    # The master saw the full working counter (2 per board with outputs, 1 per board with
    # inputs) on every cycle that came back; in the capture (which may miss frames when the
    # machine is busy) every LRW is one sent (0), one of the few answered in SAFE-OP before OP
    # (1 per board: inputs only) or one answered in OP with the full counter.
    "every LRW back with the full working counter": cycle["expected_wkc"] > 0 and
        cycle["short_wkc"] == 0 and
        0 < sum(1 for c, p, o, w in datagrams if c == LRW and w == cycle["expected_wkc"]) <= cycle["cycles"] and
        all(w in (0, cycle["process_data_slaves"], cycle["expected_wkc"])
            for c, p, o, w in datagrams if c == LRW),
}
for what, ok in checks.items():
    print(("ok: " if ok else "MISSING: ") + what)
if not all(checks.values()):
    from collections import Counter
    print("LRW working counters in the capture:", dict(Counter(w for c, p, o, w in datagrams if c == LRW)))
sys.exit(0 if all(checks.values()) else 1)
PY
echo "ok: $(tshark -r "$work/bringup.pcapng" 2>/dev/null | wc -l) frames captured, 1 malformed (sent on purpose)"

# 3. Run-time faults. A cable pulled while cycling: the cycle watchdog stops at the first short
#    working counter and the master names where the ring was cut.
start_ring "$examples/concert_paper_robot.yaml" --fault pull:elbow_2@2
rc=0
ip netns exec "$ns_master" timeout 120 "$concert" ethercat cycle --frame-timeout 200 --tries 10 --ifname "ecm$tag" --seconds 30 --lost-in-a-row 0 \
  > "$work/cycle.out" 2> "$work/cycle.err" || rc=$?
stop_ring
[ "$rc" -eq 1 ] || { cat "$work/cycle.err"; fail "cycling on a ring with a pulled cable exited $rc, not 1"; }
grep -q "working counter [0-9]* of 45: slaves 1[0-9]-19 do not answer (slave [0-9]* lost the link on port 1)" "$work/cycle.err" ||
  { cat "$work/cycle.err"; fail "the pulled cable was not named"; }
echo "ok: pulled cable: $(grep -o 'cycle [0-9]*: working.*' "$work/cycle.err")"
# A board refusing OP: named with its AL status code.
start_ring "$examples/concert_paper_robot.yaml" --fault refuse-op:yaw_2
rc=0
ip netns exec "$ns_master" timeout 120 "$concert" ethercat cycle --frame-timeout 200 --tries 10 --ifname "ecm$tag" --seconds 1 \
  > /dev/null 2> "$work/cycle.err" || rc=$?
stop_ring
[ "$rc" -eq 1 ] && grep -q "is in SAFE-OP, AL status code 0x001A (synchronization error)" "$work/cycle.err" ||
  { cat "$work/cycle.err"; fail "a board refusing OP was not named (exit $rc)"; }
echo "ok: refused OP named: $(grep -o 'slave [0-9]* (station 0x[0-9A-F]*) is in SAFE-OP, AL status code 0x001A' "$work/cycle.err")"
# A module added while the ring runs (SIGHUP re-reads the assembly): the next scan has it.
cp "$examples/concert_paper_robot.yaml" "$work/assembly.yaml"
start_ring "$work/assembly.yaml"
ip netns exec "$ns_master" timeout 120 "$concert" scan read --frame-timeout 200 --tries 10 --ifname "ecm$tag" --json > "$work/before.json" 2>/dev/null
sed -i 's/{name: drill, key: module_drill_concert, parent: yaw_3,/{name: extra_link, key: module_link_straight_400_concert, parent: yaw_3, connector: 1}\n  - {name: drill, key: module_drill_concert, parent: extra_link,/' "$work/assembly.yaml"
grep -q extra_link "$work/assembly.yaml" || fail "could not add a module to the assembly file"
kill -HUP "$ring_pid"
wait_for_line "$work/ring.log" "re-read .*: 19 -> 20 ESCs" || fail "the ring did not take the added module"
ip netns exec "$ns_master" timeout 120 "$concert" scan read --frame-timeout 200 --tries 10 --ifname "ecm$tag" --json > "$work/after.json" 2>/dev/null
stop_ring
"$concert" scan show --assembly "$work/assembly.yaml" --module-db "$db" --json > "$work/show.json"
cmp -s "$work/after.json" "$work/show.json" || fail "the scan after the module was added is not the new assembly's"
cmp -s "$work/before.json" "$work/after.json" && fail "the scan did not change when a module was added"
echo "ok: a module added at run time is in the next scan (19 -> 20 ESCs)"

# 4. The demo robot's MuJoCo model behind the drive boards (--robot): every joint found its
#    board, and every drive board reports in OP.
: > "$work/ring.log"
ip netns exec "$ns_ring" "$ring_bin" --assembly "$src/deploy/demo/drill_robot.yaml" --ifname "ecr$tag" --robot \
  > "$work/ring.log" 2>&1 &
ring_pid=$!
wait_for_line "$work/ring.log" "concert_ecat_ring: serving" || fail "the ring with the robot did not start"
grep -q "the MuJoCo robot of .*drill_robot.yaml (14 joints) behind the drive boards" "$work/ring.log" ||
  fail "the ring did not put the demo robot's 14 joints behind its boards"
ip netns exec "$ns_master" timeout 120 "$concert" ethercat cycle --frame-timeout 200 --tries 10 --ifname "ecm$tag" --seconds 1 --feedback --lost-in-a-row 0 \
  > /dev/null 2> "$work/cycle.err" || { cat "$work/cycle.err"; fail "cycling the robot's ring failed"; }
stop_ring
grep -q "joints found no drive board" "$work/ring.log" && fail "a joint of the robot found no drive board"
boards=$(grep -c "robot_id [0-9]*: status" "$work/cycle.err")
[ "$boards" -eq 15 ] || { cat "$work/cycle.err"; fail "$boards drive boards reported, expected 15"; }
echo "ok: the demo robot behind the ring: 15 drive boards report, every joint found its board"

# 5. The robot service on the ring: concert_robot --backend ethercat brings the ring to OP and
#    publishes the scan its master read; discovery and modelgen make the model from that scan;
#    the robot binds every joint to its drive board by the robot_id of the model and is ready at
#    model version 1. DDS on the master namespace's loopback, on CONCERT_DOMAIN_ID (ctest gives
#    this test a domain of its own; 80 when run by hand).
ip -n "$ns_master" link set lo up
: > "$work/ring.log"
ip netns exec "$ns_ring" "$ring_bin" --assembly "$src/deploy/demo/drill_robot.yaml" --ifname "ecr$tag" --robot \
  > "$work/ring.log" 2>&1 &
ring_pid=$!
wait_for_line "$work/ring.log" "concert_ecat_ring: serving" || fail "the ring with the robot did not start"
domain=${CONCERT_DOMAIN_ID:-80}
for service in discovery modelgen; do
  ip netns exec "$ns_master" env CONCERT_DOMAIN_ID=$domain "$build/services/$service/concert_$service" \
    > "$work/$service.log" 2>&1 &
  service_pids+=($!)
done
ip netns exec "$ns_master" env CONCERT_DOMAIN_ID=$domain "$build/services/robot/concert_robot" \
  --backend ethercat --ifname "ecm$tag" > "$work/robot.log" 2>&1 &
service_pids+=($!)
rc=0
ip netns exec "$ns_master" env CONCERT_DOMAIN_ID=$domain timeout 120 "$concert" status --until-version 1 --timeout 60 \
  --services robot > "$work/status.out" 2> "$work/status.err" || rc=$?
for pid in "${service_pids[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
# Bounded: 10 s for the services to stop, then they are killed.
for _ in $(seq 100); do
  alive=0
  for pid in "${service_pids[@]}"; do kill -0 "$pid" 2>/dev/null && alive=1; done
  [ "$alive" -eq 0 ] && break
  sleep 0.1
done
for pid in "${service_pids[@]}"; do kill -9 "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
service_pids=()
stop_ring
robot_log() { for f in robot discovery modelgen; do sed "s/^/  $f: /" "$work/$f.log" | tail -20; done; }
[ "$rc" -eq 0 ] || { cat "$work/status.err"; robot_log; fail "the robot on the ring was not ready at model version 1"; }
grep -q "concert_robot: ethercat on ecm$tag: 19 slaves, in OP" "$work/robot.log" ||
  { robot_log; fail "the robot service did not bring the ring's 19 slaves to OP"; }
grep -q "model version [0-9]* refused" "$work/robot.log" && { robot_log; fail "the robot service refused a model"; }
echo "ok: concert_robot --backend ethercat: $(grep -o 'robot@[^ ]* ready at model version [0-9]*' "$work/status.out")"
echo "PASS"

#!/usr/bin/env bash
# Teleoperation across two "machines" (issue 16), the realistic layout: the physics on
# A (the project's gripper over the floor), an operator console B with the haptic
# device (`afhub device run virtual`) and `afhub teleop`; `afhub bridge dds` on both.
# B's teleop drives A's palm through the mirror, and A's physics gives B's device its
# force feedback. Checks:
#   1. A's palm follows B's device's circle, scaled by the file's workspace scaling;
#      the palm's lag behind the device is printed (the whole loop: B's device, B's
#      teleop, B's bridge, DDS, A's bridge, A's physics, seen on A).
#   2. Pushing the device down presses A's palm on A's floor: B's device gets an
#      opposing force near the file's max force, never above it.
#   3. The world across (--world): `afhub world pause` and `resume` on B pause and
#      resume A's physics; a bridge whose command-age bound is below the link's delay
#      applies no world command.
#   4. A device across (--devices): B's device mirrored into A's hub is listed there
#      as a device, and a force commanded on A reaches it.
#   5. That device's driver restarted at once on B, its hand elsewhere: a teleop on A
#      bound to the mirror sees a new driver and re-anchors (the palm does not jump).
# The staleness B sees (mirrored states' age) and the age of the commands A applies
# are printed from the bridges' --latency reports.
# Usage: dds_teleop_two_machines_test.sh AFHUB_BINARY GRIPPER_MODEL FLOOR_MODEL. Needs root.
set -euo pipefail
test_name=dds_teleop_two_machines_test
afhub=$(realpath "$1")
gripper=$(realpath "$2")
floor=$(realpath "$3")
source "$(dirname "$0")/two_machines.sh"

# The device file on the console: the device steers A's palm, 5 x its motion; the
# palm's contact forces come back at 20 N/m, at most 3 N.
on b tee /tmp/input_devices.yaml >/dev/null <<YAML
input devices: [Console Hand]
Console Hand:
  hardware name: Virtual
  haptic gain: {linear: 20.0, angular: 0.0}
  controller gain: {linear: {P: 200, D: 16}, angular: {P: 1, D: 0.04}}
  workspace scaling: 5
  max force: 3
  simulated multibody: $gripper
  location: {position: {x: 0.6, y: 0.8, z: 0.6}, orientation: {r: 0, p: 0, y: 0}}
  button mapping: {a1: 0, a2: 1, next mode: 2, prev mode: 3}
YAML
# The hand's script (t, x, y, z): still for 2 s, four turns of a 2 cm circle of 2 s
# (starting and ending at the origin), back to rest, then 20 cm down: the palm goes
# 1 m down, onto A's floor.
awk 'BEGIN {
  pi = 3.14159265358979;
  print "0,0,0,0"; print "2,0,0,0";
  for (t = 2.05; t <= 10.001; t += 0.05) {
    a = pi * (t - 2);  # 2 s a turn
    printf "%.3f,%.6f,%.6f,0\n", t, 0.02 * cos(a) - 0.02, 0.02 * sin(a);
  }
  print "11,0,0,0"; print "13,0,0,-0.2"; print "40,0,0,-0.2";
}' | on b tee /tmp/hand.csv >/dev/null

# The loops of an operator's setup run at a real-time priority (SCHED_FIFO, inherited
# by every thread, Cyclone's too), as they would on real machines: a shared, busy test
# machine then delays them less.
rt="chrt -f 20"
palm=afhub/gripper/palm
spawn a physics $rt "$afhub" run "$gripper" "$floor"
spawn b hub "$afhub" hub
for _ in $(seq 100); do on a "$afhub" ls 2>/dev/null | grep "$palm" >/dev/null && break; sleep 0.1; done
on a "$afhub" ls | grep "$palm" >/dev/null || fail "the physics on A did not list $palm"

wait_until 60 "B's hub to start" on b "$afhub" ls
spawn a bridge_a $rt "$afhub" bridge dds --export --insecure-accept-commands --bodies 'afhub/gripper/*' --world --latency
bridge_a=$spawned
# B's bridge from a config file (the flags would do the same).
on b tee /tmp/console.yaml >/dev/null <<YAML
interface: $veth_b
mirror: true
bodies: ["afhub/gripper/*"]
world: true
qos: best-effort
YAML
spawn b bridge_b $rt "$afhub" bridge dds --config /tmp/console.yaml --latency
bridge_b=$spawned
for _ in $(seq 200); do on b "$afhub" ls 2>/dev/null | grep "$palm" >/dev/null && break; sleep 0.1; done
on b "$afhub" ls | grep "$palm" >/dev/null || fail "B does not list A's $palm"

spawn b teleop $rt "$afhub" teleop /tmp/input_devices.yaml --device hand --wait 30
teleop=$spawned
spawn b device $rt "$afhub" device run virtual --name hand --trajectory /tmp/hand.csv --max-force 10
device=$spawned
started_ns=$(date +%s%N)
# at SECONDS: sleep until that time of the hand's script.
at() {
  local left
  left=$(jq -n "$1 - ($(date +%s%N) - $started_ns) / 1e9")
  if jq -e -n "$left > 0" >/dev/null; then sleep "$left"; fi
}

echo "1. A's palm follows the circle of B's device"
at 4.5
# The palm on A and the device on B, sampled together (their stamps share the host's
# monotonic clock).
on a "$afhub" echo "$palm" --json --count 400 --rate 100 >"$work/palm.json" &
palm_reader=$!
on b "$afhub" echo device/hand --json --count 400 --rate 100 >"$work/hand.json" || fail "no device state on B"
wait "$palm_reader" || fail "no palm state on A"
python3 - "$work/palm.json" "$work/hand.json" >"$work/circle.txt" <<'PY' || { cat "$work/circle.txt"; fail "the palm did not follow the device"; }
import json, math, sys
palm = [json.loads(l) for l in open(sys.argv[1])]
hand = [json.loads(l) for l in open(sys.argv[2])]
p = [(s["publish_stamp_ns"], s["position_m"]) for s in palm]
h = [(s["stamp_ns"], s["position"]) for s in hand]
def hand_at(t):  # linear between the device's samples
    for (t0, a), (t1, b) in zip(h, h[1:]):
        if t0 <= t <= t1:
            f = (t - t0) / (t1 - t0) if t1 > t0 else 0
            return [a[i] + f * (b[i] - a[i]) for i in range(3)]
    return None
def deviations(lag_ns):
    pairs = [(q, hand_at(t - lag_ns)) for t, q in p]
    pairs = [(q, d) for q, d in pairs if d is not None]
    n = len(pairs)
    pm = [sum(q[i] for q, _ in pairs) / n for i in range(3)]
    dm = [sum(d[i] for _, d in pairs) / n for i in range(3)]
    e = sorted(math.dist([q[i] - pm[i] for i in range(3)], [5 * (d[i] - dm[i]) for i in range(3)])
               for q, d in pairs)
    radius = sum(math.hypot(q[0] - pm[0], q[1] - pm[1]) for q, _ in pairs) / n
    return n, radius, e[n // 2], e[int(0.9 * n)], e[int(0.95 * n)], e[-1]
n, radius, p50, p90, p95, worst = deviations(0)
lag = min(range(0, 100, 2), key=lambda ms: deviations(ms * 1e6)[2])
print(f"  {n} pairs: palm radius {radius:.4f} m (the device's x5: 0.1 m); the palm's distance "
      f"from the scaled device p50 {p50 * 1e3:.1f} mm, p90 {p90 * 1e3:.1f} mm, p95 {p95 * 1e3:.1f} mm, worst "
      f"{worst * 1e3:.1f} mm; smallest p50 with the device delayed by {lag} ms")
# The worst is not bounded: on a shared machine a stall of the teleop or the physics
# (tens of ms) puts the palm centimetres behind for a moment. The bulk is bounded.
sys.exit(0 if n > 200 and abs(radius - 0.1) < 0.015 and p50 < 0.004 and p95 < 0.008 else 1)
PY
cat "$work/circle.txt"

echo "2. pressing A's palm on A's floor gives B's device an opposing force"
at 14
on b "$afhub" echo device/hand --json --count 300 --rate 100 >"$work/push.json"
python3 - "$work/push.json" >"$work/push.txt" <<'PY' || { cat "$work/push.txt"; fail "no force feedback on B's device"; }
import json, math, sys
s = [json.loads(l) for l in open(sys.argv[1])]
pressing = [x for x in s if x["position"][2] < -0.15]
up = [x["applied_force"][2] for x in pressing]
most = max(math.hypot(*x["applied_force"]) for x in s)
applying = sum(x["force_gate"] == "applying" for x in s)
mean_up = sum(up) / len(up) if up else 0
print(f"  {len(pressing)} states pressing: mean force up {mean_up:.2f} N (max force 3 N), "
      f"largest {most:.2f} N, gate applying in {applying} of {len(s)}")
# The gate closes while the physics' states or the device's samples stop for 50 ms (as it
# must: 9 of 300 samples once, on a VM that held processes for 50 ms): nearly always open.
sys.exit(0 if len(pressing) > 100 and mean_up > 0.8 * 3 and most <= 3 + 1e-9 and applying >= 0.95 * len(s) else 1)
PY
cat "$work/push.txt"
kill -USR1 "$bridge_a" "$bridge_b"
sleep 0.5
grep "mirrored state age" "$work/bridge_b.log" | tail -1
grep "applied command age" "$work/bridge_a.log" | tail -1

# sim_step_of SIDE: the palm's sim step now, as published on that side.
sim_step_of() { on "$1" "$afhub" echo "$palm" --json --count 1 | jq .sim_step; }
echo "3. the world across: pause and resume A's physics from B"
kill -TERM "$teleop" "$device"
on b timeout 10 "$afhub" world pause || fail "afhub world pause on B was not confirmed"
s0=$(sim_step_of a)
sleep 0.5
s1=$(sim_step_of a)
[[ $s0 == "$s1" ]] || fail "A's physics still steps after B paused it ($s0, then $s1)"
[[ $(sim_step_of b) == "$s1" ]] || fail "B's mirror does not show A's paused step $s1"
on b timeout 10 "$afhub" world resume || fail "afhub world resume on B was not confirmed"
sleep 0.5
[[ $(sim_step_of a) -gt $s1 ]] || fail "A's physics did not resume"
echo "  paused at step $s1 from B, resumed"
# World commands older than the bound are not applied.
kill -TERM "$bridge_a"
wait "$bridge_a" || true
spawn a bridge_a2 "$afhub" bridge dds --export --insecure-accept-commands --bodies 'afhub/gripper/*' --world --max-command-age 0.000001
bridge_a=$spawned
sleep 3
# Up to three tries: under load, the new bridge's reader may not be matched yet at the
# first (world commands are not kept for late readers). None may pause A.
dropped=false
for _ in 1 2 3; do
  if on b timeout 3 "$afhub" world pause 2>/dev/null; then fail "a stale world command paused A"; fi
  kill -USR1 "$bridge_a"
  sleep 0.3
  if grep -q "device and world samples out [0-9]* in [0-9]*, commands out [0-9]* in 0, stale dropped [1-9]" \
    "$work/bridge_a2.log"; then
    dropped=true
    break
  fi
done
$dropped || fail "A's bridge did not count the stale world command it dropped"
s0=$(sim_step_of a)
sleep 0.3
[[ $(sim_step_of a) -gt $s0 ]] || fail "A's physics paused by a stale world command"
echo "  a world command older than the bound was dropped on A"

echo "4. a device across: B's device in A's hub, its force from A"
kill -TERM "$bridge_a" "$bridge_b"
spawn b device2 $rt "$afhub" device run virtual --name probe
spawned_device2=$spawned
spawn a bridge_a3 $rt "$afhub" bridge dds --export --mirror --insecure-accept-commands --bodies 'afhub/gripper/*' --devices 'probe'
spawn b bridge_b3 $rt "$afhub" bridge dds --export --mirror --insecure-accept-commands --bodies 'afhub/gripper/*' --devices 'probe'
for _ in $(seq 200); do
  [[ $(on a "$afhub" ls --json 2>/dev/null | jq -r '.[] | select(.body == "device/probe") | .kind') == device ]] && break
  sleep 0.1
done
[[ $(on a "$afhub" ls --json | jq -r '.[] | select(.body == "device/probe") | .kind') == device ]] ||
  fail "A's hub does not list B's device/probe as a device"
on a "$afhub" ls | grep "device/probe"
spawn a force $rt "$afhub" device force probe --force 0,0,1.5 --wait 10
force=$spawned
# applying_on_b: B's device applies the force commanded on A (after the ramp).
applying_on_b() {
  on b "$afhub" echo device/probe --json --count 1 |
    jq -e '.force_gate == "applying" and (.applied_force[2] - 1.5 | fabs) < 1e-6' >/dev/null
}
for _ in $(seq 100); do applying_on_b && break; sleep 0.1; done
# A second of samples, 80 % of them applying the force: a VM holding the processes for
# tens of ms closes the gate, and its ramp takes a moment to come back (CI once: fewer
# than 16 of 20 samples over 0.4 s, the last one applying).
on b "$afhub" echo device/probe --json --count 50 --rate 50 >"$work/probe.json"
kill -TERM "$force"
jq -e -s 'map(select(.force_gate == "applying" and (.applied_force[2] - 1.5 | fabs) < 1e-6)) | length >= 40' \
  "$work/probe.json" >/dev/null ||
  fail "the force commanded on A did not reach B's device: of 50 samples (gate, force z): $(jq -r -s 'map("\(.force_gate) \(.applied_force[2])") | join(", ")' "$work/probe.json")"
echo "  B's device applies the 1.5 N commanded on A"
# A's mirrored device shows the device's state, seen on A.
on a "$afhub" echo device/probe --json --count 1 | jq -e '.model == "virtual"' >/dev/null ||
  fail "A's mirror of device/probe does not carry its spec"
# Recorded on A from the mirror's own tape: every state it mirrored, a recorder held
# stopped for 100 ms included.
spawn a probe_record "$afhub" record -o /tmp/probe.mcap --devices --duration 3
recorder=$spawned
sleep 1.5
kill -STOP "$recorder"
sleep 0.1
kill -CONT "$recorder"
wait "$recorder" || fail "recording A's mirror of device/probe failed: $(cat "$work/probe_record.log")"
on a "$afhub" info /tmp/probe.mcap --json >"$work/probe_info.json"
jq -e '.channels[] | select(.topic == "/device/probe/state") | .messages > 100 and .skipped == 0'   "$work/probe_info.json" >/dev/null ||
  fail "the recording of A's mirror of device/probe skipped states: $(jq -c '.channels[] | select(.topic == "/device/probe/state")' "$work/probe_info.json")"
echo "  A's mirror of device/probe recorded: $(jq -r '.channels[] | select(.topic == "/device/probe/state") | "\(.messages) states, \(.skipped) skipped"' "$work/probe_info.json")"
echo "5. B's driver restarted at once, its hand 2 cm away: A's teleop on the mirror re-anchors"
# The mirror's pid does not change with the remote driver: it numbers the new driver's
# states afresh, as a restarted local driver's are. Without that, the palm was thrown to
# the new hand (10 cm at the scale of 5). --stale 2000: no gap seen in the samples.
on b cat /tmp/input_devices.yaml | on a tee /tmp/probe_devices.yaml >/dev/null
printf '0,0.02,0,0\n60,0.02,0,0\n' | on b tee /tmp/out.csv >/dev/null
spawn a teleop_a $rt "$afhub" teleop /tmp/probe_devices.yaml --device probe --stale 2000 --wait 30
# palm_x: A's palm's x now.
palm_x() { on a "$afhub" echo "$palm" --json --count 1 | jq .position_m[0]; }
wait_until 30 "A's teleop to drive the palm with device/probe" grep -q "device/probe drives" "$work/teleop_a.log"
sleep 1
before=$(palm_x)
{ kill -9 "$spawned_device2" && wait "$spawned_device2"; } 2>/dev/null || true
spawn b device3 $rt "$afhub" device run virtual --name probe --trajectory /tmp/out.csv
new_hand_on_a() { on a "$afhub" echo device/probe --json --count 1 | jq -e '.position[0] > 0.0195'; }
wait_until 30 "the new driver's hand on A" new_hand_on_a
on a "$afhub" echo "$palm" --json --count 100 --rate 100 >"$work/after.json"
jump=$(jq -s --argjson x0 "$before" 'map(.position_m[0] - $x0 | fabs) | max' "$work/after.json")
echo "  largest move of A's palm along x over the next second: $jump m"
jq -e -n "$jump < 0.01" >/dev/null || fail "A's palm jumped $jump m to the new driver's hand"
grep -q "device/probe has a new driver" "$work/teleop_a.log" || fail "A's teleop did not say it saw a new driver"
echo "  $(grep -o "device/probe has a new driver.*" "$work/teleop_a.log" | head -1)"
echo "$test_name: PASS"

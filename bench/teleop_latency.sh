#!/usr/bin/env bash
# Teleoperation latency (issue 15), a benchmark: a hub, `afhub run` of the project's
# gripper and the floor, the virtual device following a 2 cm circle at 1 kHz, and
# `afhub teleop --latency N`, which prints p50, p99 and max of
#   device sample -> body command: a DeviceState's publish stamp to the publish of the
#     BodyCommand computed from it (the teleop loop's wake-up and the law);
#   device sample -> device force: the same stamp to the publish stamp of the first
#     DeviceState whose applied force comes from the DeviceCommand computed from it
#     (DeviceState::command_sequence): the driver's next cycle closes the loop.
# Every stamp is CLOCK_MONOTONIC on one machine. All loops are free-running 1 ms grids
# that are not aligned, so both figures include up to a period of waiting.
#
#   bench/teleop_latency.sh [SAMPLES] [BUILD_DIR]     (defaults: 10000, build/dev)
#
# As root it runs in a private mount namespace (its own /tmp, /dev/shm, /run), so that
# its hub cannot meet another.
set -euo pipefail

samples=${1:-10000}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${2:-$root/build/dev}" && pwd)
afhub=$build/bin/afhub
[[ -x $afhub ]] || { echo "teleop_latency.sh: $afhub is missing: build it (ninja -C $build afhub)" >&2; exit 1; }

source "$root/bench/scene_script.sh"
private_namespace "$0" "$samples" "$build"

models=$root/examples/models
cat > "$work/input_devices.yaml" <<YAML
input devices: [Bench Hand]
Bench Hand:
  hardware name: Virtual
  haptic gain: {linear: 20.0, angular: 0.0}
  controller gain: {linear: {P: 200, D: 16}, angular: {P: 1, D: 0.04}}
  workspace scaling: 5
  max force: 3
  simulated multibody: $models/gripper.yaml
  location: {position: {x: 0.6, y: 0.8, z: 0.6}, orientation: {r: 0, p: 0, y: 0}}
YAML

"$afhub" hub > "$work/hub.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do "$afhub" status > /dev/null 2>&1 && break; sleep 0.1; done
"$afhub" run "$models/gripper.yaml" "$models/floor.yaml" --no-autostart > "$work/run.log" 2>&1 &
pids+=($!)
"$afhub" device run virtual --name bench --circle 0.02,2 > "$work/device.log" 2>&1 &
pids+=($!)
# One cycle per sample and a second more for the force ramp and the first reports.
"$afhub" teleop "$work/input_devices.yaml" --device bench --latency "$samples" \
  --cycles $((samples + 1000))

#!/usr/bin/env bash
# `afhub bridge dds --profile ros2` seen from the ROS 2 side (issue 16): ros2_reader,
# built from the ROS 2 IDL and Cyclone alone, reads the arm's JointState, PoseStamped,
# TwistStamped and WrenchStamped and commands its joints with a JointState. Checks:
# the reader holds no afhub code; joint names are the body's, positions match
# `afhub echo`, poses carry frame "world" and a stamp; a wrong type name matches
# nothing; a command moves the named joints and holds the others; a bad command is
# dropped with its reason; commands older than --max-command-age are dropped; without
# --accept-commands nothing reads commands. In a private namespace on the loopback.
# Usage: dds_ros2_profile_test.sh AFHUB_BINARY ARM_MODEL ROS2_READER. Needs root.
set -euo pipefail
test_name=dds_ros2_profile_test
afhub=$(realpath "$1")
model=$(realpath "$2")
reader=$(realpath "$3")
source "$(dirname "$(realpath "$0")")/private_loopback.sh"

body=afhub/arm/base
base=rt/$body

echo "1. the reader is Cyclone and the ROS 2 types only"
# Read whole, not piped into grep -q: grep leaving early would SIGPIPE nm (pipefail).
symbols=$(nm --defined-only "$reader")
if grep -qi afhub <<<"$symbols"; then fail "ros2_reader defines afhub symbols"; fi
if ldd "$reader" | grep -i afhub >/dev/null; then fail "ros2_reader links an afhub library"; fi
grep -q sensor_msgs_msg_dds__JointState__desc <<<"$symbols" ||
  fail "ros2_reader lacks the ROS 2 JointState type"

spawn physics "$afhub" run "$model"
for _ in $(seq 100); do "$afhub" ls 2>/dev/null | grep "$body" >/dev/null && break; sleep 0.1; done
"$afhub" ls | grep "$body" >/dev/null || fail "the physics did not list $body"
start_bridge() {
  spawn bridge "$afhub" bridge dds --export --profile ros2 --bodies 'afhub/arm/*' "$@"
  bridge=$spawned
}
stop_bridge() {
  kill -TERM "$bridge"
  wait "$bridge" || true
}
start_bridge --insecure-accept-commands

echo "2. JointState, PoseStamped, TwistStamped, WrenchStamped on $base/*"
"$reader" read "$base" --seconds 10 >"$work/read.json" || fail "the reader did not get every topic"
cat "$work/read.json" | cut -c1-160
expected_names=$("$afhub" ls --json | jq -c --arg b "$body" '.[] | select(.body == $b) | .joints')
names=$(jq -c 'select(.topic | endswith("/joint_states")) | .name' "$work/read.json")
[[ "$names" == "$expected_names" ]] || fail "joint names $names, expected $expected_names"
jq -e -s 'map(select(.topic | endswith("/pose")))[0] | .frame_id == "world" and .stamp > 0' \
  "$work/read.json" >/dev/null || fail "the pose lacks frame world or a stamp"
jq -e -s '[.[].stamp] | min > 0' "$work/read.json" >/dev/null || fail "a zero stamp"

echo "3. a wrong type name (sensor_msgs::msg::JointState) matches nothing"
if "$reader" read "$base" --seconds 3 --wrong-type >/dev/null 2>"$work/wrong.txt"; then
  fail "a reader with the wrong type name got a JointState"
fi
grep -q "nothing on $base/joint_states" "$work/wrong.txt" || fail "the wrong type did not miss joint_states"

echo "4. a JointState command moves the named joints; positions match afhub echo"
# Compared once the arm is there (the writer runs on while the reader reads): a busy
# machine takes longer than the 3 s it takes here.
spawn command "$reader" command "$base" base-link1=0.6,link2-link3=-0.4 --seconds 12
command=$spawned
for _ in $(seq 32); do
  sleep 0.25
  "$afhub" echo "$body" --json --count 1 | jq -c '.joint_positions' >"$work/echo.json"
  jq -e '(.[0] - 0.6 | fabs) < 0.01 and (.[2] + 0.4 | fabs) < 0.01' "$work/echo.json" >/dev/null &&
    break
done
"$reader" read "$base" --seconds 3 | jq -c 'select(.topic | endswith("/joint_states")) | .position' \
  >"$work/dds.json"
echo "  afhub echo: $(cat "$work/echo.json")"
echo "  ros2 reader: $(cat "$work/dds.json")"
jq -e -n --slurpfile e "$work/echo.json" --slurpfile d "$work/dds.json" \
  '($e[0] | length) == ($d[0] | length) and
   ([range($e[0] | length) | ($e[0][.] - $d[0][.]) | fabs] | max) < 0.02' >/dev/null ||
  fail "the reader's positions do not match afhub echo"
jq -e '(.[0] - 0.6 | fabs) < 0.05 and (.[2] + 0.4 | fabs) < 0.05 and (.[1] | fabs) < 0.05' \
  "$work/dds.json" >/dev/null || fail "the command did not move base-link1 to 0.6, link2-link3 to -0.4"
wait "$command" || fail "the command writer found no reader"

echo "5. a command naming no joint of the body is dropped, with the reason"
"$reader" command "$base" nosuch=0.5 --seconds 0.5 2>/dev/null
kill -USR1 "$bridge"
sleep 0.3
grep -q "'nosuch' is not a joint of this body (its joints: base-link1" "$work/bridge.log" ||
  fail "the bridge did not say why it dropped the command"
grep -Eq "ros2 profile: .*bad [1-9]" "$work/bridge.log" || fail "the bad commands were not counted"
stop_bridge

echo "6. with a command-age bound below the loopback's latency, commands are dropped"
start_bridge --insecure-accept-commands --max-command-age 0.000001
"$reader" command "$base" base-link1=-0.6 --seconds 3 2>/dev/null
position=$("$afhub" echo "$body" --json --count 1 | jq '.joint_positions[0]')
echo "  base-link1 at $position after 3 s of stale commands to -0.6"
jq -e -n "($position + 0.6 | fabs) > 0.3" >/dev/null || fail "stale commands were applied"
stop_bridge
grep -Eq "ros2 profile: .*stale dropped [1-9]" "$work/bridge.log" ||
  fail "the bridge did not count the stale commands"

echo "7. without --accept-commands no one reads joint_command"
start_bridge
if "$reader" command "$base" base-link1=0.2 --seconds 3 2>/dev/null; then
  fail "a bridge without --accept-commands read commands"
fi
stop_bridge
echo "$test_name: PASS"

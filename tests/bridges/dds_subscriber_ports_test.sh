#!/usr/bin/env bash
# iceoryx 2.0.3 has 1024 subscriber ports in all, and a process that asks for one when
# none is left aborts. The hub's Health counts them, and every afhub reader checks the
# count first: with all but a few taken (subscriber_port_taker), `afhub echo` exits 1
# saying how many are left, and a bridge exporting more bodies than there are ports
# left exports them all: their states are slots, read through one subscriber port of
# the bridge's (a port per body once refused some of them). In a private namespace on
# the loopback.
# Usage: dds_subscriber_ports_test.sh AFHUB_BINARY SUBSCRIBER_PORT_TAKER. Needs root.
set -euo pipefail
test_name=dds_subscriber_ports_test
afhub=$(realpath "$1")
taker=$(realpath "$2")
source "$(dirname "$(realpath "$0")")/private_loopback.sh"

bodies=10
spawn synth "$afhub" synth --namespace many --bodies "$bodies" --joints 1 --rate 200
for _ in $(seq 100); do "$afhub" ls 2>/dev/null | grep "many/body$((bodies - 1))" >/dev/null && break; sleep 0.1; done
"$afhub" ls | grep "many/body$((bodies - 1))" >/dev/null || fail "synth did not list its bodies"

take_ports_leaving() {
  spawn taker "$taker" "$1"
  taker_pid=$spawned
  for _ in $(seq 100); do grep -q holding "$work/taker.log" && break; sleep 0.1; done
  grep -q holding "$work/taker.log" || fail "the taker did not get there"
  cat "$work/taker.log"
}
give_ports_back() {
  kill -TERM "$taker_pid"
  wait "$taker_pid" || fail "the taker failed"
  # Until the hub's health counts them free again (afhub ls reads with them).
  for _ in $(seq 50); do "$afhub" ls >/dev/null 2>&1 && break; sleep 0.1; done
}

echo "1. afhub echo, with only the health reserve left, says so and exits 1"
take_ports_leaving 4
set +e
"$afhub" echo many/body0 --count 1 >"$work/echo.out" 2>"$work/echo.err"
code=$?
set -e
cat "$work/echo.err"
[[ $code -eq 1 ]] || fail "afhub echo exited $code, expected 1"
grep -Eq "needs 1 iceoryx subscriber port and the hub has [0-4] left of 1024" "$work/echo.err" ||
  fail "afhub echo did not say how many subscriber ports are left"
give_ports_back

echo "2. a bridge exporting $bodies bodies with as many ports left exports them all"
take_ports_leaving "$bodies"
spawn bridge "$afhub" bridge dds --export --bodies 'many/*'
bridge=$spawned
all_exported() {
  [[ $(grep -o "^afhub bridge dds: exporting many/body[0-9]* (" "$work/bridge.log" | sort -u | wc -l) -eq $bodies ]]
}
for _ in $(seq 100); do all_exported && break; sleep 0.1; done
kill -0 "$bridge" 2>/dev/null || fail "the bridge died"
all_exported || fail "the bridge did not export all $bodies bodies with $bodies ports left"
grep "not exporting many/" "$work/bridge.log" && fail "the bridge refused bodies"
give_ports_back
kill -TERM "$bridge"
wait "$bridge" || fail "the bridge did not exit cleanly"
grep "exported $bodies bodies" "$work/bridge.log" || fail "the bridge did not export all $bodies"
grep -q "states out [1-9]" "$work/bridge.log" || fail "no state went out"
echo "dds_subscriber_ports_test: PASS"

#!/usr/bin/env bash
# The hub going away under `afhub bridge dds` (as under every afhub process, see
# hub/client/include/afhub/hub/hub_loss.hpp): the bridge outlives it and re-attaches to
# the next hub. On one "machine" (a private namespace on the loopback): the physics
# (arm7), an exporting bridge that takes commands, a mirroring one, and a DDS peer
# (dds_peer) that publishes a body's states and commands the arm at 500 Hz. The hub is
# stopped with `afhub hub stop --force` (while commands arrive: the exporter once
# aborted there on POPO__CHUNK_LOCKING_ERROR) and SIGKILLed, twice each, and a new hub
# started each time. After each: both bridges are the same processes, said they
# re-attached, and their counters move again (the exporter's states out and commands
# in, the mirror's states in); the peer receives the arm's states again, and the new
# hub has the peer's body (`afhub echo` reads it).
# Usage: dds_hub_loss_test.sh AFHUB_BINARY ARM_MODEL DDS_PEER. Needs root. The losses
# in order: $DDS_HUB_LOSSES (default "stop kill stop kill").
set -euo pipefail
test_name=dds_hub_loss_test
afhub=$(realpath "$1")
model=$(realpath "$2")
peer=$(realpath "$3")
source "$(dirname "$(realpath "$0")")/private_loopback.sh"

body=afhub/arm/base
spawn hub0 "$afhub" hub
for _ in $(seq 100); do "$afhub" status >/dev/null 2>&1 && break; sleep 0.1; done
spawn physics "$afhub" run "$model"
physics=$spawned
for _ in $(seq 100); do "$afhub" ls 2>/dev/null | grep "$body" >/dev/null && break; sleep 0.1; done
"$afhub" ls | grep "$body" >/dev/null || fail "the physics did not list $body"
spawn exporter "$afhub" bridge dds --export --insecure-accept-commands --bodies 'afhub/arm/*' \
  --max-command-age 1
exporter=$spawned
spawn mirror "$afhub" bridge dds --mirror --bodies 'peer/*'
mirror=$spawned
spawn peer "$peer" --bodies 1 --joints 2 --prefix peer/b --state-rate 200 \
  --command "$body" --command-joints 7
dds_peer=$spawned
# Started (a SIGUSR1 before the bridge's handler would end it): each says what it bridges.
for _ in $(seq 150); do
  grep -q "exporting $body (" "$work/exporter.log" && grep -q "mirroring peer/b0" "$work/mirror.log" &&
    break
  sleep 0.1
done
grep -q "exporting $body (" "$work/exporter.log" || fail "the exporting bridge did not export $body"
grep -q "mirroring peer/b0" "$work/mirror.log" || fail "the mirroring bridge did not mirror peer/b0"

# counters NAME PID: the bridge's "STATES_OUT STATES_IN COMMANDS_OUT COMMANDS_IN" now.
counters() {
  kill -USR1 "$2"
  sleep 0.2
  grep 'states out' "$work/$1.log" | tail -1 |
    sed -E 's/.*states out ([0-9]+) in ([0-9]+), commands out ([0-9]+) in ([0-9]+),.*/\1 \2 \3 \4/'
}
peer_received() {
  grep -o 'states received [0-9]*' "$work/peer.log" | tail -1 | cut -d' ' -f3
}
# crossing: within 20 s, the exporter's states out and commands in, the mirror's states
# in, and the peer's states received all move (over 1 s).
crossing() {
  local out0 in0 mirror0 peer0 out1 in1 mirror1 peer1 _
  for _ in $(seq 20); do
    read -r out0 _ _ in0 < <(counters exporter "$exporter")
    read -r _ mirror0 _ _ < <(counters mirror "$mirror")
    peer0=$(peer_received)
    sleep 1
    read -r out1 _ _ in1 < <(counters exporter "$exporter")
    read -r _ mirror1 _ _ < <(counters mirror "$mirror")
    peer1=$(peer_received)
    echo "  exporter: states out +$((out1 - out0)), commands in +$((in1 - in0)); mirror: states in" \
      "+$((mirror1 - mirror0)); peer: states received +$((peer1 - peer0))"
    ((out1 > out0 && in1 > in0 && mirror1 > mirror0 && peer1 > peer0)) && return 0
  done
  return 1
}
hub_pid() { "$afhub" status --json 2>/dev/null | jq -r .hub_pid; }

echo "0. before any loss"
crossing || fail "states and commands do not cross"

round=0
for loss in ${DDS_HUB_LOSSES:-stop kill stop kill}; do
  round=$((round + 1))
  old_hub=$(hub_pid)
  [[ $old_hub =~ ^[0-9]+$ ]] || fail "no hub pid before round $round"
  echo "$round. the hub (pid $old_hub) $([[ $loss == stop ]] && echo "stopped with hub stop --force" || echo SIGKILLed)"
  if [[ $loss == stop ]]; then
    "$afhub" hub stop --force >/dev/null || fail "afhub hub stop --force failed"
  else
    kill -9 "$old_hub"
  fi
  for _ in $(seq 100); do kill -0 "$old_hub" 2>/dev/null || break; sleep 0.1; done
  sleep 1 # the bridges meet the loss with no hub
  for name in exporter mirror; do
    pid=${!name}
    kill -0 "$pid" 2>/dev/null || fail "the $name bridge died with the hub"
  done
  spawn "hub$round" "$afhub" hub
  for name in exporter mirror; do
    for _ in $(seq 150); do
      (($(grep -c "re-attached to the hub" "$work/$name.log" || true) >= round)) && break
      sleep 0.1
    done
    (($(grep -c "re-attached to the hub" "$work/$name.log" || true) >= round)) ||
      fail "the $name bridge did not re-attach to the new hub (round $round)"
  done
  crossing || fail "states and commands do not cross again after round $round"
  "$afhub" echo peer/b0 --count 3 >/dev/null || fail "the new hub has no state of peer/b0"
done

# (An iceoryx error on the way, as POPO__CHUNK_LOCKING_ERROR from a command applied as
# the hub's memory goes, is the hub's loss: said in the "went away" line, never fatal.)
! grep "fatal iceoryx error\|Assertion" "$work"/exporter.log "$work"/mirror.log ||
  fail "a bridge met a fatal iceoryx error"
kill -0 "$physics" || fail "the physics died"
kill -TERM "$exporter" "$mirror" "$dds_peer"
wait "$exporter" || fail "the exporting bridge did not stop cleanly"
wait "$mirror" || fail "the mirroring bridge did not stop cleanly"
echo "$test_name: PASS"

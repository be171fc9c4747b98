#!/usr/bin/env bash
# A mirroring `afhub bridge dds` claiming a newly announced body keeps carrying the
# bodies it mirrors already: the claim is held (hold_claims.c) for as long as this test
# wants, as a slow hub would hold it (a claim may wait 2.5 s for the hub's catalog and
# free ports), and meanwhile the mirrored body's states keep arriving in the hub and
# the commands a local `afhub ctl sine` writes to it keep reaching the peer. The
# claimed body's own states are dropped, counted, until its claim is done. Claims on
# the bridge's loop once stalled the commands (and devices, the world and the status)
# for as long as the claim took, and the far side dropped them as stale. On one
# "machine" (a private namespace on the loopback).
# Usage: dds_claim_off_loop_test.sh AFHUB_BINARY DDS_PEER HOLD_CLAIMS_LIBRARY. Needs root.
set -euo pipefail
test_name=dds_claim_off_loop_test
afhub=$(realpath "$1")
peer=$(realpath "$2")
hold_claims=$(realpath "$3")
source "$(dirname "$(realpath "$0")")/private_loopback.sh"

# wait_for NAME TEXT: until NAME's log has a line with TEXT (up to 30 s).
wait_for() {
  for _ in $(seq 300); do grep -qF "$2" "$work/$1.log" && return 0; sleep 0.1; done
  fail "$1 did not say '$2' within 30 s"
}
# commands_received: the commands to peer/first0 that the first peer has counted.
commands_received() {
  { grep -o 'commands received [0-9]*' "$work/first_peer.log" || echo "x x 0"; } |
    tail -1 | cut -d' ' -f3
}
# wait_for_commands COUNT: until the first peer has counted COUNT commands (up to 30 s).
wait_for_commands() {
  for _ in $(seq 300); do (($(commands_received) >= $1)) && return 0; sleep 0.1; done
  return 1
}

# dropped_awaiting_claim: asks the bridge for its status (SIGUSR1) and prints the states
# it has dropped awaiting a claim.
dropped_awaiting_claim() {
  local before
  before=$(grep -c "states dropped awaiting a claim" "$work/mirror.log" || true)
  kill -USR1 "$mirror"
  for _ in $(seq 300); do
    if (($(grep -c "states dropped awaiting a claim" "$work/mirror.log" || true) > before)); then
      grep -o "states dropped awaiting a claim [0-9]*" "$work/mirror.log" | tail -1 | cut -d' ' -f6
      return 0
    fi
    sleep 0.1
  done
  fail "the bridge gave no status within 30 s of SIGUSR1"
}

spawn hub "$afhub" hub
for _ in $(seq 100); do "$afhub" status >/dev/null 2>&1 && break; sleep 0.1; done
spawn first_peer "$peer" --bodies 1 --joints 1 --prefix peer/first --state-rate 100
spawn mirror env LD_PRELOAD="$hold_claims" AFHUB_TEST_HOLD_CLAIMS="$work/hold" \
  "$afhub" bridge dds --mirror --bodies 'peer/*'
mirror=$spawned
wait_for mirror "mirroring peer/first0"
spawn sine "$afhub" ctl sine peer/first0 --amplitude 0.1 --period 1
wait_for_commands 1 || fail "no command to the mirrored body reached the peer"

echo "1. a second body announced, its claim held"
touch "$work/hold"
spawn second_peer "$peer" --bodies 1 --joints 1 --prefix peer/second --state-rate 100
wait_for mirror "hold_claims: a claim held"
# The peer counts once a second: its count from before the hold is out after two more.
lines=$(grep -c "commands received" "$work/first_peer.log" || true)
for _ in $(seq 300); do
  (($(grep -c "commands received" "$work/first_peer.log" || true) >= lines + 2)) && break
  sleep 0.1
done
before=$(commands_received)
timeout 30 "$afhub" echo peer/first0 --count 200 >/dev/null ||
  fail "the mirrored body's states stopped arriving while a claim was held"
echo "  200 states of peer/first0 arrived while the claim was held"
wait_for_commands $((before + 200)) ||
  fail "commands to the mirrored body stopped reaching the peer while a claim was held" \
    "(received $before, then $(commands_received))"
echo "  commands received by the peer while the claim was held: $before, then $(commands_received)"
grep -q "mirroring peer/second0" "$work/mirror.log" && fail "the held claim finished"
dropped=$(dropped_awaiting_claim)
echo "  states of peer/second0 dropped awaiting its claim: $dropped"
((dropped > 0)) || fail "the states of the body being claimed were not counted as dropped"

echo "2. the claim let go: the second body mirrored"
rm "$work/hold"
wait_for mirror "mirroring peer/second0"
timeout 30 "$afhub" echo peer/second0 --count 2 >/dev/null ||
  fail "no state of the body once its claim was done"
kill -TERM "$mirror"
wait "$mirror" || fail "the mirroring bridge did not stop cleanly"
echo "$test_name: PASS"

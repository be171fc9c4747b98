#!/usr/bin/env bash
# A DDS peer (dds_peer) announcing 600 bodies to a mirroring `afhub bridge dds`, on one
# "machine" (a private namespace on the loopback). Small bodies (one joint): the bridge
# mirrors its most (--max-mirrored, default 225), refuses the rest saying why, once
# each, and a local `afhub run` still gets its bodies into the catalog (a mirror once
# took all 450 places). Bodies of 1024 joint names each: the bridge mirrors those whose
# names fit its directory, refuses the rest, and lives (it once loaned a directory
# larger than any chunk and iceoryx aborted it, MEPOO__MEMPOOL_GETCHUNK_CHUNK_IS_TOO_LARGE).
# Usage: dds_mirror_bounds_test.sh AFHUB_BINARY ARM_MODEL DDS_PEER. Needs root. The
# parts run: $DDS_MIRROR_PARTS (default "small big").
set -euo pipefail
test_name=dds_mirror_bounds_test
afhub=$(realpath "$1")
model=$(realpath "$2")
peer=$(realpath "$3")
source "$(dirname "$(realpath "$0")")/private_loopback.sh"

announced=600
spawn hub "$afhub" hub
for _ in $(seq 100); do "$afhub" status >/dev/null 2>&1 && break; sleep 0.1; done

# settle NAME: waits (up to 120 s) until the bridge has said, for every announced
# body, that it mirrors it or not; prints "MIRRORED REFUSED".
settle() {
  local mirrored=0 refused=0
  for _ in $(seq 1200); do
    mirrored=$(grep -c "^afhub bridge dds: mirroring " "$work/$1.log" || true)
    refused=$(grep -c "^afhub bridge dds: not mirroring " "$work/$1.log" || true)
    ((mirrored + refused >= announced)) && break
    kill -0 "$2" 2>/dev/null || break
    sleep 0.1
  done
  echo "$mirrored $refused"
}
# local_run NAME: `afhub run` of the arm beside the mirror lists its bodies.
local_run() {
  spawn "$1" "$afhub" run "$model"
  local physics=$spawned
  for _ in $(seq 150); do "$afhub" ls 2>/dev/null | grep afhub/arm/base >/dev/null && break; sleep 0.1; done
  "$afhub" ls | grep afhub/arm/base >/dev/null ||
    fail "a local afhub run did not get its bodies into the catalog beside the mirror"
  kill -TERM "$physics"
  wait "$physics" || fail "the local physics did not stop cleanly"
}

parts=${DDS_MIRROR_PARTS:-small big}
if [[ $parts == *small* ]]; then
echo "1. $announced small bodies announced"
spawn small_peer "$peer" --bodies "$announced" --joints 1 --prefix peer/small --state-rate 10
small_peer=$spawned
spawn small_mirror "$afhub" bridge dds --mirror --bodies 'peer/*'
mirror=$spawned
read -r mirrored refused < <(settle small_mirror "$mirror")
echo "  mirrored $mirrored, refused $refused"
kill -0 "$mirror" 2>/dev/null || fail "the mirroring bridge died"
((mirrored == 225 && refused == announced - 225)) ||
  fail "$mirrored mirrored and $refused refused, expected 225 and $((announced - 225))"
grep -q "not mirroring peer/small.*--max-mirrored" "$work/small_mirror.log" ||
  fail "the refusals do not name --max-mirrored"
[[ -z $(grep -o "not mirroring peer/small[0-9]*" "$work/small_mirror.log" | sort | uniq -d) ]] ||
  fail "a refusal was said more than once"
listed=$("$afhub" ls --json | jq '[.[] | select(.body | startswith("peer/"))] | length')
echo "  the catalog lists $listed mirrored bodies"
((listed == 225)) || fail "the catalog lists $listed mirrored bodies, not 225"
"$afhub" echo peer/small0 --count 2 >/dev/null || fail "no state of a mirrored body"
local_run physics1
kill -TERM "$mirror" "$small_peer"
wait "$mirror" || fail "the mirroring bridge did not stop cleanly"
wait "$small_peer" || true
fi

if [[ $parts == *big* ]]; then
echo "2. $announced bodies of 1024 joint names announced"
spawn big_peer "$peer" --bodies "$announced" --joints 1024 --prefix peer/big
big_peer=$spawned
spawn big_mirror "$afhub" bridge dds --mirror --bodies 'peer/*'
mirror=$spawned
read -r mirrored refused < <(settle big_mirror "$mirror")
echo "  mirrored $mirrored, refused $refused"
kill -0 "$mirror" 2>/dev/null || fail "the mirroring bridge died"
((mirrored > 0 && mirrored + refused == announced)) ||
  fail "$mirrored mirrored and $refused refused of $announced"
grep -q "not mirroring peer/big.*more than half the hub's largest chunk" "$work/big_mirror.log" ||
  fail "the refusals do not say the directory would not fit"
local_run physics2
kill -TERM "$mirror" "$big_peer"
wait "$mirror" || fail "the mirroring bridge did not stop cleanly"
fi
echo "$test_name: PASS"

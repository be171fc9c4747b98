#!/usr/bin/env bash
# `afhub bridge dds` measured between two "machines" (issue 16), in one run. Needs root
# (network and mount namespaces, tc). See tests/bridges/two_machines.sh for the set-up.
#
#   bench/dds_bridge.sh [--quick] [BUILD_DIR] [OUT_DIR]   (defaults: build/dev, ./dds-bench)
#   afhub bench dds [--quick] [--out OUT_DIR]              (the same, from a build tree)
#
# 1. Latency, 1 KiB states (a BodyState of 32 joints; a BodyCommand of 32 joints back),
#    best effort, keep last 1, one ping a millisecond, in interleaved rounds:
#      raw:    Cyclone DDS ping on A, pong on B (afhub-dds-bench raw-ping/raw-pong);
#      bridge: afhub on A -> bridge A -> DDS -> bridge B -> afhub on B, whose pong answers
#              with a command on the mirrored body -> bridge B -> DDS -> bridge A -> A.
#    Round trips: p50, p99, max of each, and what the bridge pair adds at p50; then the
#    same with idle CPUs kept polling (both bridges --cpu-wake-latency 0), and with both
#    bridges polling (--spin) instead of sleeping.
# 2. 400 bodies (AFHUB_BENCH_BODIES; 7 joints) at 1 kHz from `afhub synth` on A,
#    exported by a bridge on A, read on B by a DDS reader that prints, each second, how
#    many states came and how old they were. Over a window: the bridge's CPU per 1000
#    states sent (utime+stime from /proc/PID/stat), its heap allocations per state (the
#    tests' LD_PRELOAD counter, when built), beside those of a plain Cyclone writer of
#    the same samples (afhub-dds-bench writes), and its resident memory. Then overload:
#    reliable QoS, a reader that takes every 100 ms, and A's link limited to 20 Mbit/s
#    (tc tbf): the bridge's memory stays flat and the states that arrive stay young
#    (newest wins; nothing queues).
# Writes OUT_DIR/raw_rtt_ns.txt, bridge_rtt_ns.txt (one round trip a line),
# load_normal.jsonl, load_overload.jsonl (the reader's seconds), and summary.txt.
# bench/dds_bridge_plot.sh OUT_DIR PNG draws them.
set -euo pipefail

# Short rounds, many of them: the scheduler's placement of the threads on this VM's
# cores changes the round trips by tens of us from one minute to the next, and each
# path must see as many of those placements as the other.
rounds=20
pings=500
window=10
# Each body takes two of iceoryx 2.0.3's 1024 subscriber ports here (the synth's
# command reader, the bridge's state reader; the hub's rate probes take 32 in all).
bodies=${AFHUB_BENCH_BODIES:-400}
if [[ ${1:-} == --quick ]]; then
  rounds=8
  pings=250
  window=5
  shift
fi
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$root/build/dev}" && pwd)
mkdir -p "${2:-dds-bench}"
out=$(cd "${2:-dds-bench}" && pwd)
afhub=$build/bin/afhub
bench=$build/bin/afhub-dds-bench
for binary in "$afhub" "$bench"; do
  [[ -e $binary ]] || {
    echo "dds_bridge.sh: $binary is missing: ninja -C $build afhub afhub-dds-bench" >&2
    exit 1
  }
done
# Allocations are counted with the tests' LD_PRELOAD library when it is built.
malloc_count=$build/tests/libmalloc_count.so
preload=LD_PRELOAD=$malloc_count
[[ -e $malloc_count ]] || preload=AFHUB_NO_MALLOC_COUNT=1
if [[ $EUID -ne 0 ]]; then
  echo "dds_bridge.sh: needs root (ip netns, mount namespaces, tc)" >&2
  exit 1
fi
rm -f "$out"/raw_rtt_ns*.txt "$out"/bridge_rtt_ns*.txt "$out"/load_*.jsonl

test_name="afhub bench dds"
source "$root/tests/bridges/two_machines.sh"

spawn a hub_a "$afhub" hub
spawn b hub_b "$afhub" hub
for side in a b; do
  for _ in $(seq 100); do on "$side" "$afhub" status >/dev/null 2>&1 && break; sleep 0.1; done
done

# p50 p99 max of a file of nanoseconds, in microseconds.
quantiles() {
  sort -n "$1" | awk '{v[NR] = $1} END {
    printf "%.1f %.1f %.1f %d", v[int(0.5 * (NR - 1)) + 1] / 1e3, v[int(0.99 * (NR - 1)) + 1] / 1e3, v[NR] / 1e3, NR }'
}

echo "1. latency: $rounds rounds of $pings pings, raw DDS and through the bridges"
# latency SUFFIX [BRIDGE FLAGS]: interleaved rounds of raw and bridged pings, into
# raw_rtt_nsSUFFIX.txt and bridge_rtt_nsSUFFIX.txt.
latency() {
  local suffix=$1
  shift
  spawn a bridge_a "$afhub" bridge dds --export --insecure-accept-commands --bodies 'bench/*' "$@"
  local bridge_a=$spawned
  spawn b bridge_b "$afhub" bridge dds --mirror --bodies 'bench/*' "$@"
  local bridge_b=$spawned
  spawn b raw_pong "$bench" raw-pong
  local raw_pong=$spawned
  spawn b hub_pong "$bench" hub-pong
  local hub_pong=$spawned
  for round in $(seq "$rounds"); do
    on a "$bench" raw-ping "$pings" "$out/raw_rtt_ns$suffix.txt"
    on a "$bench" hub-ping "$pings" "$out/bridge_rtt_ns$suffix.txt"
  done
  for pid in "$hub_pong" "$raw_pong" "$bridge_b" "$bridge_a"; do stop "$pid"; done
}
latency ""
read -r raw50 raw99 rawmax rawn <<<"$(quantiles "$out/raw_rtt_ns.txt")"
read -r hub50 hub99 hubmax hubn <<<"$(quantiles "$out/bridge_rtt_ns.txt")"
# Each variant changes the machine for raw DDS too (the wake-up limit is the host's;
# polling bridges take the cores), so raw DDS is measured again beside it.
echo "   again with idle CPUs polling (--cpu-wake-latency 0)"
latency _wake --cpu-wake-latency 0
read -r wraw50 wraw99 wrawmax wrawn <<<"$(quantiles "$out/raw_rtt_ns_wake.txt")"
read -r whub50 whub99 whubmax whubn <<<"$(quantiles "$out/bridge_rtt_ns_wake.txt")"
echo "   again with both bridges polling (--spin)"
latency _spin --spin
read -r sraw50 sraw99 srawmax srawn <<<"$(quantiles "$out/raw_rtt_ns_spin.txt")"
read -r shub50 shub99 shubmax shubn <<<"$(quantiles "$out/bridge_rtt_ns_spin.txt")"

# cpu_ticks PID: utime + stime (clock ticks).
cpu_ticks() { awk '{print $14 + $15}' "/proc/$1/stat"; }
rss_kib() { awk '/VmRSS/ {print $2}' "/proc/$1/status"; }
# counts PID LOG: "ALLOCATIONS STATES_OUT" of the bridge now.
counts() {
  [[ $preload == LD_PRELOAD=* ]] && kill -USR2 "$1"  # without the library, USR2 would kill
  kill -USR1 "$1"
  sleep 0.3
  local allocations states
  allocations=$(grep -o 'malloc-count: [0-9]*' "$2" | tail -1 | cut -d' ' -f2)
  [[ -n $allocations ]] || allocations=0  # not counted
  states=$(grep -o 'states out [0-9]*' "$2" | tail -1 | cut -d' ' -f3)
  echo "$allocations $states"
}

# window NAME: measures the export bridge over $window seconds while the reader on B
# prints its seconds to load_NAME.jsonl. Sets cpu_per_1000, allocs_per_state, rate,
# rss_first, rss_max, rss_last and rss_series (KiB, once a second).
window() {
  local name=$1 ticks0 ticks1 a0 s0 a1 s1 rss
  read -r a0 s0 <<<"$(counts "$bridge" "$work/bridge_load.log")"
  ticks0=$(cpu_ticks "$bridge")
  rss_first=$(rss_kib "$bridge")
  rss_max=$rss_first
  spawn b "sink_$name" "$bench" sink "$window"
  local sink=$spawned
  rss_series=""
  for _ in $(seq "$window"); do
    sleep 1
    rss=$(rss_kib "$bridge")
    rss_series="$rss_series $rss"
    ((rss > rss_max)) && rss_max=$rss
  done
  rss_last=$rss
  ticks1=$(cpu_ticks "$bridge")
  read -r a1 s1 <<<"$(counts "$bridge" "$work/bridge_load.log")"
  wait "$sink" || true
  cp "$work/sink_$name.log" "$out/load_$name.jsonl"
  local hz
  hz=$(getconf CLK_TCK)
  cpu_per_1000=$(jq -n "($ticks1 - $ticks0) / $hz * 1000 / ($s1 - $s0) * 1000")  # ms
  allocs_per_state=$(jq -n "($a1 - $a0) / ($s1 - $s0)")
  rate=$(jq -n "($s1 - $s0) / $window")
}

echo "2. $bodies bodies at 1 kHz exported"
spawn a synth "$afhub" synth --namespace load --bodies "$bodies" --joints 7 --rate 1000 --no-autostart
for _ in $(seq 100); do on a "$afhub" ls 2>/dev/null | grep "load/body$((bodies - 1))" >/dev/null && break; sleep 0.1; done
spawn a bridge_load env "$preload" "$afhub" bridge dds --export --bodies 'load/*'
bridge=$spawned
sleep 4  # the catalog scan, discovery, warm caches
window normal
normal="states sent $(printf %.0f "$rate")/s; CPU $(printf %.3f "$cpu_per_1000") ms per 1000 states; \
$(printf %.2f "$allocs_per_state") heap allocations per state in the bridge process; RSS ${rss_first} -> ${rss_last} KiB"
echo "  $normal"
stop "$bridge"
# The same writes from a plain Cyclone writer: the allocations that are Cyclone's own.
cyclone_allocs="not counted (build malloc_count)"
if [[ $preload == LD_PRELOAD=* ]]; then
  spawn b sink_writes "$bench" sink 6
  sink=$spawned
  sleep 2
  on a env "$preload" "$bench" writes "$bodies" 100000 >"$work/writes.log" 2>&1
  wait "$sink" || true
  cyclone_allocs=$(grep -o 'malloc-count: [0-9]*' "$work/writes.log" | cut -d' ' -f2 | paste -sd' ' |
    awk '{printf "%.2f", ($2 - $1) / 100000}')
fi
normal="$normal; a plain Cyclone writer: $cyclone_allocs allocations per write"
echo "  Cyclone alone: $cyclone_allocs allocations per dds_write"

echo "   overload: reliable, a reader taking every 100 ms, A's link at 20 Mbit/s"
ip netns exec "$ns_a" tc qdisc add dev "$veth_a" root tbf rate 20mbit burst 32kbit latency 50ms
spawn a bridge_load env "$preload" "$afhub" bridge dds --export --reliable --bodies 'load/*'
bridge=$spawned
sleep 4
export AFHUB_DDS_BENCH_RELIABLE=1 AFHUB_DDS_BENCH_SLOW_MS=100
window overload
unset AFHUB_DDS_BENCH_RELIABLE AFHUB_DDS_BENCH_SLOW_MS
overload="states written $(printf %.0f "$rate")/s; RSS ${rss_first} KiB first, then by second${rss_series} KiB; \
reader: $(jq -s -r '[.[].states] | add' "$out/load_overload.jsonl") states in ${window} s, \
age p50 by second $(jq -s -r '[.[].age_p50_us / 1000 | floor] | map(tostring) | join(" ")' "$out/load_overload.jsonl") ms"
echo "  $overload"
stop "$bridge"

{
  echo "afhub bench: dds bridge, $(date -u +%F), $(nproc) cores, $(uname -r)"
  echo "1 KiB round trip (us)     p50     p99     max      n"
  printf "raw Cyclone DDS      %8s %8s %8s %6s\n" "$raw50" "$raw99" "$rawmax" "$rawn"
  printf "afhub via 2 bridges  %8s %8s %8s %6s\n" "$hub50" "$hub99" "$hubmax" "$hubn"
  echo "bridge pair adds at p50: $(jq -rn "$hub50 - $raw50 | . * 10 | round / 10") us"
  printf "with idle CPUs polling (both bridges --cpu-wake-latency 0):\n"
  printf "raw Cyclone DDS      %8s %8s %8s %6s\n" "$wraw50" "$wraw99" "$wrawmax" "$wrawn"
  printf "afhub via 2 bridges  %8s %8s %8s %6s\n" "$whub50" "$whub99" "$whubmax" "$whubn"
  echo "bridge pair adds at p50: $(jq -rn "$whub50 - $wraw50 | . * 10 | round / 10") us"
  printf "with both bridges polling (--spin):\n"
  printf "raw Cyclone DDS      %8s %8s %8s %6s\n" "$sraw50" "$sraw99" "$srawmax" "$srawn"
  printf "afhub via 2 bridges  %8s %8s %8s %6s\n" "$shub50" "$shub99" "$shubmax" "$shubn"
  echo "bridge pair adds at p50: $(jq -rn "$shub50 - $sraw50 | . * 10 | round / 10") us"
  echo "$bodies bodies at 1 kHz: $normal"
  echo "overload: $overload"
} | tee "$out/summary.txt"

#!/usr/bin/env bash
# What recording costs (issue 32), measured, never asserted:
#   1. The example scene (19 bodies) simulated at 1 kHz by `afhub run`, with `afhub ctl
#      sine` commanding its arm, alternately without and with `afhub record --commands`
#      running beside it (PAIRS pairs of runs, STEPS steps each): each run's step p50 and
#      p99 from `afhub run --report`, and the ratio of the medians with and without.
#      Then one run of as many steps as all those pairs, with the recorder started and
#      stopped every 2 s: the steps (`afhub run --step-log`) while it records and while
#      it does not, p50 and p99 of each. Both sides share the run, so the VM's drift from
#      one run to the next (2x in p99) is not in their ratio. Then window by window: each
#      recording window's p50 and p99 over the mean of the windows without just before and
#      after it, and, as the measure's own noise, the same for each window without against
#      its two neighbours without (medians, quartiles).
#   2. A thousand bodies at 1 kHz from `afhub synth --bodies 1000 --joints 8` (a stand-in
#      for a physics, which takes about 1 ms a step for a thousand bodies on the project's
#      2-core VM) recorded for SECONDS s: messages/s, MB/s into the file, dropped and
#      missed updates, and the recorder's CPU (user + system time over wall time).
#
#   bench/record_bench.sh [SECONDS] [PAIRS] [STEPS] [BUILD_DIR]
#       PHYSICS_ARGS="--fifo 50" (say): more options for the scene's `afhub run`
#       (defaults: 60 s, 3 pairs, 10000 steps, build/dev)
#
# As root it runs in a private mount namespace (its own /tmp, /dev/shm, /run). The files
# are written to /tmp there (a tmpfs: the disk's speed is not what is measured).
set -euo pipefail

seconds=${1:-60}
pairs=${2:-3}
steps=${3:-10000}
physics_args=${PHYSICS_ARGS:-}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${4:-$root/build/dev}" && pwd)
afhub=$build/bin/afhub
[[ -x $afhub ]] || { echo "record_bench.sh: $afhub is missing: build it" >&2; exit 1; }

source "$root/bench/scene_script.sh"
private_namespace "$0" "$seconds" "$pairs" "$steps" "$build"

"$afhub" hub > "$work/hub.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do "$afhub" status > /dev/null 2>&1 && break; sleep 0.1; done

# CPU seconds (user + system) of process $1 so far.
cpu_seconds() {
  awk -v tick="$(getconf CLK_TCK)" '{ print ($14 + $15) / tick }' "/proc/$1/stat"
}

echo "== the example scene at 1 kHz, $steps steps a run: step time without and with the recorder"
p99s_without=() p99s_with=()
for pair in $(seq "$pairs"); do
  for recorded in 0 1; do
    report=$work/run-$pair-$recorded.json
    "$afhub" run --launch "$root/examples/models/launch.yaml" -l 0,1,2 --paused --steps "$steps" \
      --report "$report" --no-autostart $physics_args > "$work/run.log" 2>&1 &
    run=$!
    "$afhub" ctl sine arm/base --wait 30 > "$work/ctl.log" 2>&1 &
    ctl=$!
    recorder=""
    if [[ $recorded == 1 ]]; then
      "$afhub" record --overwrite -o "$work/scene.mcap" --commands > "$work/record.log" 2>&1 &
      recorder=$!
    fi
    sleep 2  # the controller and the recorder join before the first step
    "$afhub" world resume > /dev/null
    wait "$run"
    kill "$ctl" 2> /dev/null || true
    [[ -n $recorder ]] && kill -INT "$recorder" && wait "$recorder" || true
    wait "$ctl" 2> /dev/null || true
    read -r p50 p99 < <(python3 -c "import json,sys; t=json.load(open(sys.argv[1]))['step_time_us']; print(t['p50'], t['p99'])" "$report")
    printf 'run %d %-15s step p50 %6.1f us  p99 %6.1f us%s\n' "$pair" \
      "$([[ $recorded == 1 ]] && echo 'with recorder' || echo 'without')" "$p50" "$p99" \
      "$([[ $recorded == 1 ]] && echo "  ($(tail -1 "$work/record.log" | sed 's/^afhub record: //'))")"
    if [[ $recorded == 1 ]]; then p99s_with+=("$p99"); else p99s_without+=("$p99"); fi
  done
done
python3 - "${p99s_without[*]}" "${p99s_with[*]}" <<'PY'
import statistics, sys
without = [float(x) for x in sys.argv[1].split()]
with_ = [float(x) for x in sys.argv[2].split()]
a, b = statistics.median(without), statistics.median(with_)
print(f"median step p99: {a:.1f} us without, {b:.1f} us with the recorder: {b / a:.3f}x")
PY

toggle_steps=$((2 * pairs * steps))
echo "== the example scene at 1 kHz, one run of $toggle_steps steps, the recorder on and off every 2 s"
# CLOCK_MONOTONIC (the step log's clock) from bash's own clock, with no process started
# inside the windows: the offset between the two, read once.
offset_ns=$(python3 -c 'import time; print(time.time_ns() - time.monotonic_ns())')
monotonic_ns() { echo $((${EPOCHREALTIME//[!0-9]/} * 1000 - offset_ns)); }
"$afhub" run --launch "$root/examples/models/launch.yaml" -l 0,1,2 --paused --steps "$toggle_steps" \
  --step-log "$work/steps.log" --no-autostart $physics_args > "$work/run.log" 2>&1 &
run=$!
"$afhub" ctl sine arm/base --wait 30 > "$work/ctl.log" 2>&1 &
ctl=$!
sleep 2
"$afhub" world resume > /dev/null
: > "$work/windows.txt"
while kill -0 "$run" 2> /dev/null; do
  on=$(monotonic_ns)
  "$afhub" record --overwrite -o "$work/toggle.mcap" --commands > "$work/toggle.log" 2>&1 &
  recorder=$!
  sleep 2
  off=$(monotonic_ns)
  kill -INT "$recorder" && wait "$recorder" || true
  echo "$on $off $(monotonic_ns)" >> "$work/windows.txt"  # started, stopped, gone
  sleep 2
done
wait "$run"
kill "$ctl" 2> /dev/null || true
wait "$ctl" 2> /dev/null || true
python3 - "$work/steps.log" "$work/windows.txt" <<'PY'
import statistics, sys
steps = [tuple(map(float, line.split()[:2])) for line in open(sys.argv[1]).readlines()[1:]]
windows = [tuple(map(int, line.split())) for line in open(sys.argv[2]) if line.strip()]
# Recording: from 0.5 s after the recorder started (it has joined) until it was stopped;
# not recording: from 0.3 s after it exited (its file closed) until the next start.
on, off = [], []
for i, (start, stop, gone) in enumerate(windows):
    next_start = windows[i + 1][0] if i + 1 < len(windows) else float("inf")
    on.append([d for t, d in steps if start + 5e8 <= t <= stop])
    off.append([d for t, d in steps if gone + 3e8 <= t <= next_start])
def percentile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]
every_on, every_off = sum(on, []), sum(off, [])
if not every_on or not every_off:
    print("no steps in one of the windows: a longer run is needed (PAIRS x STEPS)")
    sys.exit(0)
a50, a99 = percentile(every_off, .5), percentile(every_off, .99)
b50, b99 = percentile(every_on, .5), percentile(every_on, .99)
print(f"not recording: {len(every_off)} steps, p50 {a50:.1f} us, p99 {a99:.1f} us")
print(f"recording:     {len(every_on)} steps, p50 {b50:.1f} us, p99 {b99:.1f} us")
print(f"step p99 with the recorder: {b99 / a99:.3f}x, p50 {b50 / a50:.3f}x ({len(windows)} windows)")
# Window by window, so that a burst of the VM's noise weighs one window rather than the
# pooled p99: each recording window against the mean of the windows without it just
# before and after (which cancels a drift); and, as the measure's own noise in the same
# run, each window without against its two neighbours without.
def against_neighbours(middle, before, after, q):
    return [percentile(m, q) / ((percentile(b, q) + percentile(a, q)) / 2)
            for m, b, a in zip(middle, before, after) if m and b and a]
def summary(values):
    if len(values) < 2:
        return "too few windows"
    q = statistics.quantiles(values, n=4)
    return f"median {statistics.median(values):.3f}x (quartiles {q[0]:.3f} to {q[2]:.3f}, {len(values)} windows)"
for name, q in (("p50", .5), ("p99", .99)):
    print(f"window by window, {name} recording / not:", summary(against_neighbours(on[1:], off, off[1:], q)))
    print(f"window by window, {name} not / not (the noise):", summary(against_neighbours(off[1:], off, off[2:], q)))
PY

echo "== a thousand bodies at 1 kHz (afhub synth, 8 joints: 1184-byte states), recorded for $seconds s"
"$afhub" synth --bodies 1000 --joints 8 --no-autostart > "$work/synth.log" 2>&1 &
pids+=($!)
sleep 3
for compression in zstd lz4 none; do
  "$afhub" record --overwrite -o "$work/thousand.mcap" --duration "$seconds" --compression "$compression" \
    > "$work/thousand.log" 2>&1 &
  recorder=$!
  start=$(date +%s.%N)
  cpu=0
  while kill -0 "$recorder" 2> /dev/null; do
    cpu=$(cpu_seconds "$recorder" 2> /dev/null || echo "$cpu")
    sleep 0.5
  done
  end=$(date +%s.%N)
  python3 - "$compression" "$work/thousand.log" "$cpu" "$start" "$end" \
    "$(stat -c %s "$work/thousand.mcap")" <<'PY'
import re, sys
line = [l for l in open(sys.argv[2]) if l.startswith("afhub record: recorded")][-1]
number = lambda pattern: float(re.search(pattern, line).group(1))
recorded, messages = number(r"recorded ([0-9.]+) s"), number(r"(\d+) messages")
dropped, missed = number(r"dropped (\d+)"), number(r"missed (\d+)")
cpu, wall, size = float(sys.argv[3]), float(sys.argv[5]) - float(sys.argv[4]), int(sys.argv[6])
published = messages + dropped + missed
print(f"{sys.argv[1]:>5}: {messages / recorded:,.0f} messages/s written, {size / recorded / 1e6:.1f} MB/s "
      f"into the file, dropped {100 * dropped / published:.1f} %, missed {100 * missed / published:.1f} % "
      f"of {published / recorded:,.0f} updates/s; recorder CPU {100 * cpu / wall:.0f} % of one core")
PY
  rm -f "$work/thousand.mcap"
done

#!/usr/bin/env bash
# The browser viewer's cost to the physics loop (issue 17), in ONE physics run: the
# example scene runs in real time at 1 kHz (`afhub run --cpu 0 --step-log`), and
# windows of WINDOW seconds alternate between no viewer at all and a viewer with two
# clients: two WebSocket readers (bench/ws_reader.py, the cheap variant), two headless
# Chromium pages (software WebGL, SwiftShader), and two Chromium pages pinned to the
# other CPU (taskset). Each window starts once its clients are connected and settled.
# For each window: the step time's p50 and p99 from the physics' own step log, the
# p99's ratio to the mean of the windows without a viewer around it, the viewer's CPU
# (utime + stime from /proc/PID/stat) and the clients' CPU, as % of one core.
#
#   bench/viewer_cost.sh [WINDOW_S] [ROUNDS] [BUILD_DIR] [FIFO]
#                        (defaults: 10, 2, build/dev, 0)
# FIFO > 0 runs the physics loop at that SCHED_FIFO priority with its memory locked
# (`afhub run --fifo FIFO --lock-memory`, as root), as a real-time deployment would.
#
# As root it runs in a private mount namespace (its own /tmp, /dev/shm, /run), so that
# its hub cannot meet another. Needs chromium. A measurement, not a test: on a shared
# machine other loads move the figures.
set -euo pipefail

window=${1:-10}
rounds=${2:-2}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${3:-$root/build/dev}" && pwd)
fifo=${4:-0}
realtime=()
[[ $fifo -gt 0 ]] && realtime=(--fifo "$fifo" --lock-memory)
afhub=$build/bin/afhub
[[ -x $afhub ]] || { echo "viewer_cost.sh: $afhub is missing: build it (ninja -C $build afhub)" >&2; exit 1; }
command -v chromium > /dev/null || { echo "viewer_cost.sh: chromium is missing (apt-get install chromium)" >&2; exit 1; }

source "$root/bench/scene_script.sh"
private_namespace "$0" "$window" "$rounds" "$build" "$fifo"

cpus=$(nproc)
other_cpu=$((cpus > 1 ? 1 : 0))
tick=$(getconf CLK_TCK)
conditions=(none websockets none browsers none browsers-pinned none)
# Every window, its settling and the starts and stops: at most 30 s beyond WINDOW.
steps=$((rounds * ${#conditions[@]} * (window + 30) * 1000))

now_ns() { python3 -c 'import time; print(time.monotonic_ns())'; }
# CPU ticks (user + system) of the given processes, the ended ones not counted.
ticks() {
  local sum=0 pid stat
  for pid in "$@"; do
    stat=$(cat "/proc/$pid/stat" 2>/dev/null) || continue
    stat=${stat##*) }  # after the command name, which may hold spaces
    sum=$((sum + $(awk '{print $12 + $13}' <<< "$stat")))
  done
  echo "$sum"
}
browser_pids() { pgrep -f -- "--user-data-dir=$work/profile" || true; }
clients_connected() { ss -Htn state established "( sport = :$port )" | wc -l; }

"$afhub" hub > "$work/hub.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do "$afhub" status > /dev/null 2>&1 && break; sleep 0.1; done
"$afhub" run --launch "$root/examples/models/launch.yaml" -l 0,1,2 --no-autostart --cpu 0 \
  "${realtime[@]}" --steps "$steps" --step-log "$work/steps.txt" > "$work/run.log" 2>&1 &
physics=$!
pids+=($physics)
sleep 3

view=""
clients=()
start_condition() {  # start_condition CONDITION
  [[ $1 == none ]] && return
  "$afhub" view --port 0 > "$work/view.log" 2>&1 &
  view=$!
  for _ in $(seq 100); do grep -q 'http://' "$work/view.log" && break; sleep 0.1; done
  port=$(grep -o '127.0.0.1:[0-9]*' "$work/view.log" | head -1 | cut -d: -f2)
  clients=()
  for client in 1 2; do
    case $1 in
      websockets) "$root/bench/ws_reader.py" "$port" > "$work/reader$client.log" 2>&1 & ;;
      browsers | browsers-pinned)
        pin=()
        [[ $1 == browsers-pinned ]] && pin=(taskset -c "$other_cpu")
        "${pin[@]}" chromium --headless=new --no-sandbox --use-gl=swiftshader \
          --enable-unsafe-swiftshader --window-size=800,600 --remote-debugging-port=0 \
          --user-data-dir="$work/profile$client" "http://127.0.0.1:$port/" > /dev/null 2>&1 &
        ;;
    esac
    clients+=($!)
  done
  # Connected, and past the page's loading (a software-rendered page takes seconds).
  for _ in $(seq 300); do [[ $(clients_connected) -ge 2 ]] && break; sleep 0.1; done
  [[ $1 == websockets ]] && sleep 2 || sleep 8
}
stop_condition() {
  [[ -z $view ]] && return
  for client in "${clients[@]}"; do kill "$client" 2>/dev/null || true; done
  for client in "${clients[@]}"; do wait "$client" 2>/dev/null || true; done
  kill "$view"
  wait "$view" 2>/dev/null || true
  view=""
  sleep 2  # the browsers' processes gone
}

: > "$work/windows.txt"
for round in $(seq "$rounds"); do
  for condition in "${conditions[@]}"; do
    [[ $round -gt 1 && $condition == none && -s $work/windows.txt ]] &&
      [[ $(tail -1 "$work/windows.txt" | cut -d' ' -f1) == none ]] && continue
    start_condition "$condition"
    browsers=$(browser_pids)
    view_before=$( [[ -n $view ]] && ticks "$view" || echo 0)
    clients_before=$(ticks "${clients[@]}" $browsers)
    begin=$(now_ns)
    sleep "$window"
    end=$(now_ns)
    view_after=$( [[ -n $view ]] && ticks "$view" || echo 0)
    clients_after=$(ticks "${clients[@]}" $browsers)
    connected=$( [[ -n $view ]] && clients_connected || echo 0)
    echo "$condition $begin $end $((view_after - view_before)) $((clients_after - clients_before)) $connected" >> "$work/windows.txt"
    stop_condition
  done
done
kill -TERM "$physics"
wait "$physics" || true
readers=$(cat "$work"/reader*.log 2>/dev/null | tr '\n' ' ')

grep -i "fifo\|lock" "$work/run.log" || true
python3 - "$work/steps.txt" "$work/windows.txt" "$tick" "$window" "$readers" <<'PY'
import sys
steps_file, windows_file, tick, window, readers = sys.argv[1:]
tick = float(tick)
samples = []
with open(steps_file) as f:
    next(f)
    for line in f:
        begin, us = line.split()
        samples.append((int(begin), float(us)))
def percentile(values, q):
    values = sorted(values)
    return values[min(len(values) - 1, int(q * len(values)))] if values else float("nan")
windows = []
for line in open(windows_file):
    name, begin, end, view_ticks, client_ticks, connected = line.split()
    begin, end = int(begin), int(end)
    times = [us for t, us in samples if begin <= t < end]
    seconds = (end - begin) * 1e-9
    windows.append(dict(name=name, seconds=seconds, steps=len(times), p50=percentile(times, 0.5),
                        p99=percentile(times, 0.99), view=100 * int(view_ticks) / tick / seconds,
                        clients=100 * int(client_ticks) / tick / seconds, connected=int(connected)))
print("one physics run, %s s windows; step time (us) from its step log" % window)
print("%-16s %5s %6s %8s %8s %9s %9s %10s %8s" % ("window", "s", "steps", "p50", "p99", "p99/base",
                                              "view CPU", "client CPU", "clients"))
for i, w in enumerate(windows):
    ratio = ""
    if w["name"] != "none":
        around = [windows[j]["p99"] for j in (i - 1, i + 1)
                  if 0 <= j < len(windows) and windows[j]["name"] == "none"]
        if around:
            ratio = "%.3f" % (w["p99"] / (sum(around) / len(around)))
    print("%-16s %5.1f %6d %8.1f %8.1f %9s %8.1f%% %9.1f%% %8s" % (
        w["name"], w["seconds"], w["steps"], w["p50"], w["p99"], ratio, w["view"], w["clients"],
        w["connected"] if w["name"] != "none" else "-"))
if readers.strip():
    print("ws_reader.py clients received: " + readers.strip())
PY

#!/usr/bin/env bash
# The browser viewer's cost to the physics loop (issue 17), in ONE run of two identical
# physics processes: the example scene twice (the second under `--namespace twin`),
# both pinned to CPU 0 at 1 kHz, each writing its step log. Windows of WINDOW seconds
# alternate between no viewer at all and a viewer watching the FIRST one with two
# clients: two WebSocket readers (bench/ws_reader.py, the cheap variant), two headless
# Chromium pages (software WebGL, SwiftShader), and two Chromium pages pinned to the
# other CPU (taskset). The twin is the control: it runs in the same windows, on the same
# CPU, through the same load, with no viewer, so the machine's noise (which moves a
# window's p99 by tens of %) divides out.
# For each window: both loops' step time p50 and p99 (as `afhub run` times a step:
# commands in, step, states out), the p99 ratio watched / twin, and that ratio over
# the same ratio in the no-viewer windows around it (1.000: the viewer costs nothing
# measurable); the viewer's CPU (utime + stime from /proc/PID/stat) and its clients',
# as % of one core. Then each kind of window pooled.
#
#   bench/viewer_cost.sh [WINDOW_S] [ROUNDS] [BUILD_DIR] [FIFO]
#                        (defaults: 10, 2, build/dev, 0)
# FIFO > 0 runs both physics loops at that SCHED_FIFO priority with their memory locked
# (`afhub run --fifo FIFO --lock-memory`, as root), as a real-time deployment would.
#
# As root it runs in a private mount namespace (its own /tmp, /dev/shm, /run), so that
# its hub cannot meet another. Needs chromium. A measurement, not a test.
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
physics=()
for twin in watched twin; do
  name_space=()
  [[ $twin == twin ]] && name_space=(--namespace twin)
  "$afhub" run --launch "$root/examples/models/launch.yaml" -l 0,1,2 --no-autostart --cpu 0 \
    "${name_space[@]}" "${realtime[@]}" --steps "$steps" --step-log "$work/steps-$twin.txt" \
    > "$work/run-$twin.log" 2>&1 &
  physics+=($!)
  pids+=($!)
done
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
kill -TERM "${physics[@]}"
wait "${physics[@]}" || true
readers=$(cat "$work"/reader*.log 2>/dev/null | tr '\n' ' ')

grep -ih "fifo\|lock" "$work"/run-*.log || true
python3 - "$work/steps-watched.txt" "$work/steps-twin.txt" "$work/windows.txt" "$tick" "$window" \
  "$readers" <<'PY'
import math
import sys
watched_file, twin_file, windows_file, tick, window, readers = sys.argv[1:]
tick = float(tick)
def steps(path):
    with open(path) as f:
        next(f)
        return [(int(begin), float(us)) for begin, us, *_ in (line.split() for line in f)]
watched, twin = steps(watched_file), steps(twin_file)
def percentile(values, q):  # afhub's one rule (rt/percentile.hpp): nearest rank
    values = sorted(values)
    return values[max(1, math.ceil(q * len(values))) - 1] if values else float("nan")
def inside(samples, spans):
    return [us for t, us in samples if any(b <= t < e for b, e in spans)]
windows = []
for line in open(windows_file):
    name, begin, end, view_ticks, client_ticks, connected = line.split()
    begin, end = int(begin), int(end)
    seconds = (end - begin) * 1e-9
    w = dict(name=name, begin=begin, end=end, seconds=seconds,
             view=100 * int(view_ticks) / tick / seconds,
             clients=100 * int(client_ticks) / tick / seconds, connected=int(connected))
    for key, samples in (("w", watched), ("t", twin)):
        times = inside(samples, [(begin, end)])
        w[key + "steps"], w[key + "p50"], w[key + "p99"] = (
            len(times), percentile(times, 0.5), percentile(times, 0.99))
    w["ratio"] = w["wp99"] / w["tp99"]
    windows.append(w)
print("one run of two identical physics loops on CPU 0, %s s windows; step times (us) from "
      "their step logs; the viewer watches the first" % window)
print("%-16s %6s %7s %7s %8s %8s %7s %10s %9s %10s" % (
    "window", "steps", "p50", "p99", "twin p50", "twin p99", "ratio", "ratio/base", "view CPU",
    "client CPU"))
for i, w in enumerate(windows):
    relative = ""
    if w["name"] != "none":
        around = [windows[j]["ratio"] for j in (i - 1, i + 1)
                  if 0 <= j < len(windows) and windows[j]["name"] == "none"]
        if around:
            relative = "%.3f" % (w["ratio"] / (sum(around) / len(around)))
    print("%-16s %6d %7.1f %7.1f %8.1f %8.1f %7.3f %10s %8.1f%% %9.1f%%" % (
        w["name"], w["wsteps"], w["wp50"], w["wp99"], w["tp50"], w["tp99"], w["ratio"], relative,
        w["view"], w["clients"]))
print("pooled over all windows of a kind (the same seconds for both loops):")
for kind in ("none", "websockets", "browsers", "browsers-pinned"):
    spans = [(w["begin"], w["end"]) for w in windows if w["name"] == kind]
    if not spans:
        continue
    mine, other = inside(watched, spans), inside(twin, spans)
    print("  %-16s %6d steps: p99 %.1f us, twin %.1f us, ratio %.3f" % (
        kind, len(mine), percentile(mine, 0.99), percentile(other, 0.99),
        percentile(mine, 0.99) / percentile(other, 0.99)))
print("ratio: p99 of the watched loop / p99 of its twin; /base: over the same ratio in the "
      "no-viewer windows beside it. Clients connected: " +
      " ".join(str(w["connected"]) for w in windows if w["name"] != "none"))
if readers.strip():
    print("ws_reader.py clients received: " + readers.strip())
PY

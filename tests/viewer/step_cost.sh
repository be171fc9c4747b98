#!/usr/bin/env bash
# The viewer's cost to the physics loop: `afhub run` of the example scene for SECONDS,
# alone, then with `afhub view` and two headless Chromium pages connected; prints the
# step time p50/p99 of each run and the viewer's CPU use. A measurement, not a test:
# run it in a private mount namespace (see the README), on a quiet machine.
#   tests/viewer/step_cost.sh build/release/bin/afhub [SECONDS]
set -euo pipefail
afhub=$1
seconds=${2:-20}
models=$(dirname "$0")/../../examples/models
work=$(mktemp -d)

"$afhub" hub >"$work/hub.log" 2>&1 &
hub=$!
sleep 1

run_physics() {  # run_physics REPORT
  "$afhub" run --launch "$models/launch.yaml" -l 0,1,2 --steps $((seconds * 1000)) \
    --report "$1" >/dev/null 2>&1
}
step_times() {
  python3 -c "import json,sys; r=json.load(open(sys.argv[1]))['step_time_us']; \
print('p50 %.1f us, p99 %.1f us, max %.1f us' % (r['p50'], r['p99'], r['max']))" "$1"
}

run_physics "$work/alone.json"
echo "alone:              $(step_times "$work/alone.json")"

run_physics "$work/viewed.json" &
physics=$!
sleep 2
"$afhub" view --port 0 >"$work/view.log" 2>&1 &
view=$!
sleep 1
port=$(grep -o '127.0.0.1:[0-9]*' "$work/view.log" | cut -d: -f2)
browsers=()
for profile in 1 2; do
  chromium --headless=new --no-sandbox --use-gl=swiftshader --enable-unsafe-swiftshader \
    --user-data-dir="$work/profile$profile" --remote-debugging-port=$((9300 + profile)) \
    "http://127.0.0.1:$port/" >/dev/null 2>&1 &
  browsers+=($!)
done
ticks_before=$(awk '{print $14 + $15}' /proc/$view/stat)
wait $physics
ticks_after=$(awk '{print $14 + $15}' /proc/$view/stat)
echo "two browsers:       $(step_times "$work/viewed.json")"
echo "afhub view CPU:     $(python3 -c "print('%.1f %%' % (100.0 * ($ticks_after - $ticks_before) / $(getconf CLK_TCK) / ($seconds - 3)))") of one core"
kill "${browsers[@]}" "$view"
wait "${browsers[@]}" "$view" 2>/dev/null || true
kill $hub
wait $hub || true
rm -rf "$work"

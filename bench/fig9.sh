#!/usr/bin/env bash
# The seed paper's Fig. 9 (issue 18): several closed-loop robots in one world, each
# commanded in position mode by its own `afhub ctl sine` process at 1 kHz. Runs the scene
# free-running (physics and controllers each on their own 1 ms grid), in lockstep paced at
# 1 kHz, and in lockstep as fast as it goes, and prints the physics step's p50 and p99, the
# achieved rate and the largest loop-joint gap, and how each robot's first joint tracks its
# sinusoid (RMS and largest error between its commanded and its measured position over the
# steps it had a command), from each run's `afhub run --report`.
#
#   bench/fig9.sh [STEPS] [BUILD_DIR]     (defaults: 10000 steps, build/dev)
#
# The scene: with ../shared/ambf_models, the da Vinci ECM twice, the project's RCM arm and
# the KUKA; without it, the project's 7-DOF arm and its RCM arm twice. A second copy of a
# model is moved aside (place_copy, into a temporary file) so that the copies do not
# overlap. The ECM's file gives its joints no gains (AMBF's default P 10, I 0, D 1 barely
# moves it): `--default-gains 1000,0,10` gives them to every joint whose file gives none.
# The project's RCM and 7-DOF arm give theirs VELOCITY output with P 5 and P 10, a lag of
# 1/P s: `--gains afhub/rcm/base=50,0,0` (every joint below the base) gives them P 50.
# The KUKA's file gives its own. As root it runs in a private mount namespace (its
# own /tmp, /dev/shm, /run), so that its hub cannot meet another.
set -euo pipefail

steps=${1:-10000}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${2:-$root/build/dev}" && pwd)
afhub=$build/bin/afhub
place_copy=$build/bin/place_copy
for tool in "$afhub" "$place_copy"; do
  [[ -x $tool ]] || { echo "fig9.sh: $tool is missing: build it (ninja -C $build afhub place_copy)" >&2; exit 1; }
done

source "$root/bench/scene_script.sh"
private_namespace "$0" "$steps" "$build"

shared=$root/../shared/ambf_models/descriptions/multi-bodies/robots
examples=$root/examples/models
# Each robot: its root body, its first joint (the report's name) and an amplitude (rad
# or m) inside its joints' limits.
if [[ -d $shared ]]; then
  "$place_copy" "$shared/blender-ecm.yaml" 1.5 0 0 > "$work/ecm copy.yaml"
  files=("$shared/blender-ecm.yaml" "$work/ecm copy.yaml" "$examples/rcm.yaml" "$shared/blender-kuka.yaml")
  bodies=(ambf/env/ecm/baselink ambf/env/ecm/baselink1 afhub/rcm/base ambf/env/base)
  first_joints=(ambf/env/ecm/baselink-yawlink ambf/env/ecm/baselink-yawlink1 afhub/rcm/base-yaw_link ambf/env/base-link1)
  amplitudes=(0.1 0.1 0.2 0.2)
  gains=(--default-gains 1000,0,10 --gains afhub/rcm/base=50,0,0)
  scene="ECM x2 (../shared), RCM, KUKA"
else
  "$place_copy" "$examples/rcm.yaml" 0 2 0 > "$work/rcm copy.yaml"
  files=("$examples/arm7.yaml" "$examples/rcm.yaml" "$work/rcm copy.yaml")
  bodies=(afhub/arm/base afhub/rcm/base afhub/rcm/base1)
  first_joints=(afhub/arm/base-link1 afhub/rcm/base-yaw_link afhub/rcm/base-yaw_link1)
  amplitudes=(0.3 0.2 0.2)
  gains=(--gains afhub/arm/base=50,0,0 --gains afhub/rcm/base=50,0,0 --gains afhub/rcm/base1=50,0,0)
  scene="arm7, RCM x2 (the project's own models)"
fi
robots=${#bodies[@]}

"$afhub" hub > "$work/hub.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do "$afhub" status > /dev/null 2>&1 && break; sleep 0.1; done

# run MODE REPORT [afhub run options...]: the physics with one controller per robot.
run() {
  local mode=$1 report=$2
  shift 2
  local controllers=()
  for i in "${!bodies[@]}"; do
    local extra=()
    [[ $mode == lockstep ]] && extra=(--lockstep)
    "$afhub" ctl sine "${bodies[$i]}" --amplitude "${amplitudes[$i]}" --period 4 --wait 60 \
      "${extra[@]}" > "$work/ctl$i.log" 2>&1 &
    controllers+=($!)
  done
  pids+=("${controllers[@]}")
  "$afhub" run "${files[@]}" "${gains[@]}" --steps "$steps" --report "$report" "$@" > "$work/run.log" 2>&1 ||
    { echo "fig9.sh: afhub run failed:" >&2; tail -5 "$work/run.log" >&2; exit 1; }
  for pid in "${controllers[@]}"; do kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; done
}

run free "$work/free.json"
run lockstep "$work/lockstep.json" --lockstep --wait-for "$robots" --wait-timeout 60
run lockstep "$work/fast.json" --lockstep --wait-for "$robots" --wait-timeout 60 --fast

echo "Fig. 9: $scene, $robots robots, one 'afhub ctl sine' process each at 1 kHz (period 4 s), $steps steps, ${gains[*]}"
printf '| %-36s | %9s | %9s | %15s | %15s |\n' "run" "step p50" "step p99" "rate (steps/s)" "max joint error"
printf '| %-36s | %9s | %9s | %15s | %15s |\n' "---" "---" "---" "---" "---"
for entry in "free-running, real time:free" "lockstep, real time:lockstep" "lockstep, --fast:fast"; do
  python3 - "${entry%%:*}" "$work/${entry##*:}.json" <<'PY'
import json, sys
report = json.load(open(sys.argv[2]))
step = report["step_time_us"]
print("| %-36s | %6.0f us | %6.0f us | %15.0f | %12.4f mm |" % (
    sys.argv[1], step["p50"], step["p99"], report["steps"] / report["wall_time_s"],
    report["max_joint_error_m"] * 1e3))
PY
done

# Tracking: each robot's first joint, RMS / largest error over the steps it had a command.
echo
printf '| %-34s | %9s | %21s | %21s | %21s |\n' "robot's first joint" "amplitude" "free-running RMS / max" "lockstep RMS / max" "--fast RMS / max"
printf '| %-34s | %9s | %21s | %21s | %21s |\n' "---" "---" "---" "---" "---"
for i in "${!bodies[@]}"; do
  python3 - "${first_joints[$i]}" "${amplitudes[$i]}" \
    "$work/free.json" "$work/lockstep.json" "$work/fast.json" <<'PY'
import json, sys
joint, amplitude = sys.argv[1], float(sys.argv[2])
cells = []
for path in sys.argv[3:]:
    tracking = json.load(open(path))["joints"][joint].get("tracking")
    if tracking is None:
        cells.append("no command arrived")
    else:
        cells.append("%.4f / %.4f" % (tracking["rms_error"], tracking["max_error"]))
print("| %-34s | %9.2f | %21s | %21s | %21s |" % (joint, amplitude, *cells))
PY
done

#!/usr/bin/env bash
# An installed afhub works on its own: `cmake --install` to a prefix, the examples
# built against it with find_package(afhub) (a controller, and the simulation
# embedded in a program), the installed `afhub run` simulating the installed
# example arm, and the controller moving a joint.
# Nothing installed may point into the build tree.
#   install_test.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build_dir=$1
source_dir=$2
work=$3
prefix=$work/prefix
rm -rf "$work" && mkdir -p "$work"
cmake --install "$build_dir" --prefix "$prefix" > "$work/install.log"

# The program's strings (not its debug information, which names the sources' build).
if readelf -p .rodata "$prefix/bin/afhub" | grep -F "$build_dir" ||
  grep -rlF "$build_dir" "$prefix/lib/cmake"; then
  echo "install_test: the installed afhub points into the build tree $build_dir (above)" >&2
  exit 1
fi

for example in wave_controller embedded_simulation; do
  cmake -S "$source_dir/examples/$example" -B "$work/$example" -G Ninja \
    -DCMAKE_PREFIX_PATH="$prefix" > "$work/$example-configure.log"
  cmake --build "$work/$example" > "$work/$example-build.log"
done

# The physics library alone, in a program of the user's: the arm's joints driven
# to 0.5 rad for 2 s; the shoulder gets there.
"$work/embedded_simulation/embedded_simulation" "$prefix/share/afhub/models/arm7.yaml" base 0.5 2 \
  > "$work/embedded.txt"
shoulder=$(awk '$1 == "afhub/arm/link1-link2" {print $2}' "$work/embedded.txt")
echo "install_test: the embedded simulation drove the arm's shoulder to $shoulder rad (target 0.5)"
python3 -c "import sys; sys.exit(0 if abs($shoulder - 0.5) < 0.05 else 1)" || {
  echo "install_test: the embedded simulation did not drive the shoulder to 0.5 rad" >&2
  cat "$work/embedded.txt" >&2
  exit 1
}

# A bad argument is an error with a message and exit 1, never std::terminate
# (std::stod throws std::invalid_argument, not afhub::Error).
set +e
"$work/embedded_simulation/embedded_simulation" "$prefix/share/afhub/models/arm7.yaml" base \
  not-a-number 2 > /dev/null 2> "$work/embedded-bad.txt"
status=$?
set -e
if [ "$status" -ne 1 ] || ! grep -q "embedded_simulation: error: " "$work/embedded-bad.txt"; then
  echo "install_test: a bad target made embedded_simulation exit $status, not 1 with a message:" >&2
  cat "$work/embedded-bad.txt" >&2
  exit 1
fi

# Only the installed afhub is reachable; the hub it starts is stopped at the end.
export PATH="$prefix/bin:/usr/bin:/bin"
unset AFHUB_EXECUTABLE AFHUB_MODELS
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null || true; done
  wait 2> /dev/null || true
  afhub hub stop > /dev/null 2>&1 || true
}
trap cleanup EXIT

# wait_for WHAT COMMAND...: retries the command for up to 20 s.
wait_for() {
  local what=$1
  shift
  for _ in $(seq 200); do
    "$@" > /dev/null 2>&1 && return 0
    sleep 0.1
  done
  echo "install_test: $what did not come within 20 s" >&2
  cat "$work"/*.log >&2
  exit 1
}
afhub hub > "$work/hub.log" 2>&1 &
pids+=($!)
wait_for "the hub" afhub ls
afhub run "$prefix/share/afhub/models/arm7.yaml" > "$work/run.log" 2>&1 &
pids+=($!)
wait_for "the arm" afhub echo arm/base --count 1
"$work/wave_controller/wave_controller" arm/base > "$work/controller.log" 2>&1 &
pids+=($!)

# The controller swings joint 0 by +-0.5 rad at 0.5 Hz: within 4 s it passes 0.3 rad.
afhub echo arm/base --json --count 4000 --timeout 10 > "$work/states.jsonl" 2> "$work/echo.log" || {
  echo "install_test: no states from arm/base" >&2
  cat "$work/run.log" "$work/controller.log" "$work/echo.log" >&2
  exit 1
}
largest=$(python3 -c '
import json, sys
print(max(abs(json.loads(line)["joint_positions"][0]) for line in open(sys.argv[1])))' \
  "$work/states.jsonl")
echo "install_test: the example controller moved joint 0 of arm/base up to $largest rad"
python3 -c "import sys; sys.exit(0 if $largest > 0.3 else 1)" || {
  echo "install_test: joint 0 stayed within 0.3 rad: the controller did not move the arm" >&2
  cat "$work/run.log" "$work/controller.log" >&2
  exit 1
}

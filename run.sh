#!/usr/bin/env bash
# afhub's one entry point for a Debian 12 machine (run as root, or with sudo for apt):
#   ./run.sh demo   install what is missing, build, run the demo
#   ./run.sh test   install what is missing, build, run every test; then the unit, fuzz
#                   and a chosen set of integration tests again under AddressSanitizer
#                   and UndefinedBehaviorSanitizer (labels: see tests/CMakeLists.txt)
#   ./run.sh sanitize  every test under the sanitizers
#   ./run.sh build  install what is missing and build (build/release/bin/afhub)
# The tests need root: each hub test runs in private mount and network namespaces, so
# they run in parallel and never meet a hub the demo left running.
# Each step is skipped when nothing changed, so a second run is quick.
set -euo pipefail
cd "$(dirname "$0")"

# What the build and the product need; then what only the tests run (`./run.sh test`
# installs those while it builds).
BUILD_PACKAGES=(
  g++ cmake ninja-build pkg-config clang-format
  iceoryx libiceoryx-posh-dev libiceoryx-hoofs-dev libacl1-dev
  libcli11-dev libyaml-cpp-dev libbullet-dev libassimp-dev libeigen3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # URDF robots: liburdfdom parses them (TinyXML, its XML parser, locates errors);
  # Orocos KDL is the tests' independent reference
  liburdfdom-dev libtinyxml-dev liborocos-kdl-dev libkdl-parser-dev
  # the tests' strict JSON reader (tests only)
  nlohmann-json3-dev
  # afhub bench: the transports it compares with, the machine's floor, the plot
  cyclonedds-dev cyclonedds-tools libroscpp-dev libstd-msgs-dev python3-rosmaster
  rt-tests gnuplot-nox
  # device drivers: evdev input devices, USB (Falcon), and their emulation in tests
  libevdev-dev libusb-1.0-0-dev umockdev libumockdev-dev
  # afhub view: its web server and three.js
  libcivetweb-dev libjs-three
  # `import afhub` (pybind11 over the hub client; states as numpy arrays)
  pybind11-dev python3-dev python3-numpy
  # afhub record: MCAP chunks compressed as LZ4 frames or zstd (CRC-32 from zlib)
  liblz4-dev libzstd-dev zlib1g-dev
)
TEST_PACKAGES=(
  # the viewer's tests: the browser, its image checks, the page's JavaScript syntax check
  chromium python3-pil nodejs
  # afhub bridge dds: its tests' JSON checks, and the DDS Security credentials
  jq openssl
  # the tests' private namespaces and their documentation check
  util-linux iproute2 python3
  # the Python tests, and the rospy afhub is compared with (python/examples/bench_python.py)
  python3-pytest python3-rospy
  # stack traces of a process a test finds hung (stack_traces in tests/support)
  gdb
)

# install_packages PACKAGE...: those not installed yet.
install_packages() {
  local missing=()
  for package in "$@"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
      missing+=("$package")
  done
  [ ${#missing[@]} -eq 0 ] && return
  echo "run.sh: installing ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  [ -n "$APT_UPDATED" ] || $sudo apt-get update -qq
  APT_UPDATED=1
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# The recordings' independent reader (tests/record/mcap_check): npm's @mcap/core, with
# the versions its lock file pins, into build/mcap_check (once per lock file), and the
# checker beside them.
install_mcap_check() {
  local source=tests/record/mcap_check target=build/mcap_check
  command -v npm >/dev/null || install_packages npm
  if ! cmp -s "$source/package-lock.json" "$target/package-lock.json" || [ ! -d "$target/node_modules" ]; then
    mkdir -p "$target"
    cp "$source/package.json" "$source/package-lock.json" "$target/"
    # Its lock file stays only beside a whole install: a failed one is tried again.
    (cd "$target" && npm ci --no-audit --no-fund --loglevel=error) ||
      { rm -f "$target/package-lock.json"; return 1; }
  fi
  cp "$source"/*.mjs "$target/"  # beside its node_modules, where node resolves imports
}

# The two builds: optimised with line tables (enough for a backtrace, a third cheaper to
# compile than full debug information), and the sanitizers' at -O1. There GCC 12 warns
# of "maybe uninitialized" members inside libstdc++'s own <regex> (a false positive of
# -O1 with ASan); the release build keeps that warning.
# The optimised build leaves out the unit and fuzz tests' programs: `test` builds and
# runs those under the sanitizers only, so that no test source is compiled twice.
RELEASE=(build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DAFHUB_UNIT_TESTS=OFF)
SANITIZE=(build/sanitize -DCMAKE_BUILD_TYPE=Debug -DAFHUB_SANITIZE=ON "-DCMAKE_CXX_FLAGS_DEBUG=-O1 -g1 -Wno-maybe-uninitialized")

# build DIR [cmake options...] [-- targets...]
build() {
  local dir=$1 options=() targets=()
  shift
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do options+=("$1"); shift; done
  [ $# -gt 0 ] && shift && targets=(--target "$@")
  # (Configured again each time, quickly, so that a tree made with other options follows.)
  cmake -S . -B "$dir" -G Ninja -DAFHUB_WARNINGS_AS_ERRORS=ON "${options[@]}" >/dev/null
  cmake --build "$dir" --parallel "$(nproc)" "${targets[@]}"
}

# run_tests DIR SLOTS [ctest options...]: SLOTS tests at once; a test with real-time
# bounds takes one more slot than there are cores (tests/CMakeLists.txt), so it runs alone
# when SLOTS is that.
SLOTS=$(($(nproc) + 1))
# Under the sanitizers a test per core: their processes run two to three times slower,
# and three at once on two cores starved each other's hubs past the tests' waits.
SANITIZED_SLOTS=$(nproc)
run_tests() {
  local dir=$1 slots=$2
  shift 2
  ctest --test-dir "$dir" --output-on-failure --parallel "$slots" "$@"
  # Tests skip only for a reason they print (the AMBF corpus beside the project is
  # missing, say): say how many, and why.
  local log="$dir/Testing/Temporary/LastTest.log" skipped
  local one_skip='^\[  SKIPPED \] [A-Za-z].* ([0-9]* ms)$'
  skipped=$(grep -c "$one_skip" "$log" || true)
  if [ "$skipped" -gt 0 ]; then
    echo "run.sh: $skipped tests skipped, because:"
    grep -B1 "$one_skip" "$log" | grep -v "$one_skip\|^--$" | sort | uniq -c
  fi
}

# phase NAME COMMAND...: runs it and keeps its time, printed when the script ends.
PHASES=()
phase() {
  local name=$1 start=$SECONDS
  shift
  "$@"
  PHASES+=("$(printf '%-16s %4d s' "$name" $((SECONDS - start)))")
}
# background_phase [--stoppable] NAME LOG COMMAND...: the same, started in the
# background with its output in LOG; `finish_background_phase` waits for it, and shows
# LOG if it failed. Should another phase fail meanwhile, a stoppable one (a build) is
# ended at once with what it started; any other is waited for (an install ended midway
# would leave dpkg or node_modules half done).
background_phase() {
  BACKGROUND_STOPPABLE=""
  [ "$1" = "--stoppable" ] && BACKGROUND_STOPPABLE=1 && shift
  local name=$1 log=$2
  shift 2
  BACKGROUND_NAME=$name BACKGROUND_LOG=$log
  # (Its time is its own, kept when it ends: the phases beside it may end later.)
  ( local start=$SECONDS status=0
    "$@" || status=$?
    echo $((SECONDS - start)) >"$log.seconds"
    exit $status ) >"$log" 2>&1 &
  BACKGROUND_PID=$!
}
finish_background_phase() {
  local status=0
  wait "$BACKGROUND_PID" || status=$?
  BACKGROUND_PID=""
  if [ $status -ne 0 ]; then
    cat "$BACKGROUND_LOG"
    echo "run.sh: $BACKGROUND_NAME failed (its output is above)" >&2
    return $status
  fi
  PHASES+=("$(printf '%-16s %4d s (beside the phases before it)' "$BACKGROUND_NAME" "$(cat "$BACKGROUND_LOG.seconds")")")
}
BACKGROUND_PID="" BACKGROUND_STOPPABLE=""
APT_UPDATED=""
# at_idle_priority COMMAND...: runs it only on CPU time nothing else wants (SCHED_IDLE,
# inherited by its children): a test waking for its next 1 kHz period preempts it at once.
at_idle_priority() {
  chrt --idle -p 0 "$BASHPID" >/dev/null
  "$@"
}
# descendants PID: the pids of its children, theirs, and so on.
descendants() {
  local child
  for child in $(cat /proc/"$1"/task/*/children 2>/dev/null); do
    echo "$child"
    descendants "$child"
  done
}
print_phases() {
  local status=$?
  # A phase that failed leaves none running beside it: a stoppable background one goes
  # with what it started (listed first, as killing it orphans them).
  if [ -n "$BACKGROUND_PID" ] && [ -n "$BACKGROUND_STOPPABLE" ]; then
    kill $(descendants "$BACKGROUND_PID") "$BACKGROUND_PID" 2>/dev/null || true
  elif [ -n "$BACKGROUND_PID" ]; then
    wait "$BACKGROUND_PID" 2>/dev/null || true
  fi
  [ ${#PHASES[@]} -gt 0 ] && printf 'run.sh: %s\n' "${PHASES[@]}" "$(printf '%-16s %4d s' total $SECONDS)"
  exit $status
}
trap print_phases EXIT

test_setup() {
  install_packages "${TEST_PACKAGES[@]}"
  install_mcap_check
}

check_format() {
  find shm_layout hub rt physics controllers device_drivers bench viewer bridges record cli tests examples -name '*.[ch]pp' -print0 | xargs -0 clang-format --dry-run --Werror
}

case "${1:-}" in
  demo)
    install_packages "${BUILD_PACKAGES[@]}"
    build "${RELEASE[@]}"
    exec build/release/bin/afhub demo "${@:2}"
    ;;
  test)
    phase packages install_packages "${BUILD_PACKAGES[@]}"
    mkdir -p build
    background_phase test-packages build/test-packages.log test_setup
    phase format check_format
    phase build build "${RELEASE[@]}"
    finish_background_phase
    # The real-time tests have the machine to themselves. The others wait more than they
    # compute: the sanitizer build takes the CPU they leave, at idle priority, so that it
    # never delays them (beside the real-time tests, even at idle priority, it once made
    # half of them miss their bounds: docs/testing.md).
    phase real-time-tests run_tests build/release "$SLOTS" -L real-time
    background_phase --stoppable sanitize-build build/sanitize-build.log \
      at_idle_priority build "${SANITIZE[@]}" -- sanitize_selection
    phase tests run_tests build/release "$SLOTS" -L integration -LE real-time
    finish_background_phase
    phase sanitize-tests run_tests build/sanitize "$SANITIZED_SLOTS" -L 'unit|fuzz|sanitize'
    ;;
  sanitize)
    phase packages install_packages "${BUILD_PACKAGES[@]}" "${TEST_PACKAGES[@]}"
    phase mcap-check install_mcap_check
    phase sanitize-build build "${SANITIZE[@]}"
    phase sanitize-tests run_tests build/sanitize "$SANITIZED_SLOTS"
    ;;
  build)
    install_packages "${BUILD_PACKAGES[@]}"
    build "${RELEASE[@]}"
    ;;
  *)
    echo "usage: ./run.sh demo|test|sanitize|build" >&2
    exit 2
    ;;
esac

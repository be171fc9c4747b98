#!/usr/bin/env bash
# afhub's one entry point for a Debian 12 machine (run as root, or with sudo for apt):
#   ./run.sh demo   install what is missing, build, run the demo
#   ./run.sh test   install what is missing, build, run every test, then again under
#                   AddressSanitizer and UndefinedBehaviorSanitizer
#   ./run.sh build  install what is missing and build (build/release/bin/afhub)
# Each step is skipped when nothing changed, so a second run is quick.
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(
  g++ cmake ninja-build pkg-config
  iceoryx libiceoryx-posh-dev libiceoryx-hoofs-dev libacl1-dev
  libcli11-dev libyaml-cpp-dev libbullet-dev libassimp-dev libeigen3-dev
  libgtest-dev libgmock-dev libbenchmark-dev clang-format
  # afhub bench: the transports it compares with, the machine's floor, the plot
  cyclonedds-dev cyclonedds-tools libroscpp-dev libstd-msgs-dev python3-rosmaster
  rt-tests gnuplot-nox
  # device drivers: evdev input devices, USB (Falcon), and their emulation in tests
  libevdev-dev libusb-1.0-0-dev umockdev libumockdev-dev
  # afhub view: its web server, three.js, and the browser and image checks of its tests
  libcivetweb-dev libjs-three chromium python3-pil
  # afhub bridge dds: its tests' JSON checks, and the DDS Security credentials
  jq openssl
)

install_packages() {
  local missing=()
  for package in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
      missing+=("$package")
  done
  [ ${#missing[@]} -eq 0 ] && return
  echo "run.sh: installing ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

# build DIR [cmake options...]
build() {
  local dir=$1
  shift
  if [ ! -f "$dir/build.ninja" ]; then
    cmake -S . -B "$dir" -G Ninja -DAFHUB_WARNINGS_AS_ERRORS=ON "$@"
  fi
  cmake --build "$dir" --parallel "$(nproc)"
}

run_tests() {
  local dir=$1
  # Hub tests hold the iceoryx_roudi resource lock; the others run in parallel.
  ctest --test-dir "$dir" --output-on-failure --parallel "$(nproc)"
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

case "${1:-}" in
  demo)
    install_packages
    build build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo
    exec build/release/bin/afhub demo "${@:2}"
    ;;
  test)
    install_packages
    # The code follows .clang-format.
    find shm_layout hub rt physics controllers device_drivers bench viewer bridges cli tests examples -name '*.[ch]pp' -print0 | xargs -0 clang-format --dry-run --Werror
    build build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo
    run_tests build/release
    build build/sanitize -DCMAKE_BUILD_TYPE=Debug -DAFHUB_SANITIZE=ON
    run_tests build/sanitize
    ;;
  build)
    install_packages
    build build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo
    ;;
  *)
    echo "usage: ./run.sh demo|test|build" >&2
    exit 2
    ;;
esac

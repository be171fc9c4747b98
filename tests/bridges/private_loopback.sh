# Sourced by the DDS bridge tests that need one "machine" of their own: re-runs the
# calling script in new mount and network namespaces (a private /tmp, /dev/shm and
# /run, so its hub collides with no other; only a loopback interface, so no DDS
# traffic reaches a real network), and gives it:
#   $work            a scratch directory, its logs shown when the test fails
#   spawn NAME CMD   runs CMD in the background logging to $work/NAME.log; sets $spawned
#   fail MESSAGE     fails the test
# Needs root. The caller sets $test_name first.
if [[ -z "${AFHUB_PRIVATE_LOOPBACK:-}" ]]; then
  if [[ $EUID -ne 0 ]]; then
    echo "$test_name: needs root for the private namespaces" >&2
    exit 1
  fi
  exec env AFHUB_PRIVATE_LOOPBACK=1 unshare -m -n --propagation private bash "$0" "$@"
fi
# The private /tmp keeps the source tree, ../shared and the test's arguments (the
# program, models) when they live under /tmp (a clone there).
root_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
source "$root_dir/tests/support/private_tmp.sh"
mount_private_tmp "$root_dir" "$root_dir/../shared" "$@"
mount -t tmpfs tmpfs /dev/shm
mount -t tmpfs tmpfs /run
ip link set lo up
export CYCLONEDDS_URI='<General><Interfaces><NetworkInterface name="lo"/></Interfaces></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30</MaxAutoParticipantIndex></Discovery>'
work=$(mktemp -d /tmp/afhub-test.XXXXXX)
declare -a started=()

cleanup() {
  local status=$?
  set +e
  for pid in "${started[@]}"; do kill -9 "$pid" 2>/dev/null; done
  # And whatever else runs in this network namespace: the hub `afhub run` started in
  # the background, which would outlive the test.
  local own_net proc
  own_net=$(readlink /proc/self/ns/net)
  for proc in /proc/[0-9]*; do
    [[ ${proc#/proc/} == "$$" ]] && continue
    [[ $(readlink "$proc/ns/net" 2>/dev/null) == "$own_net" ]] && kill -9 "${proc#/proc/}" 2>/dev/null
  done
  wait 2>/dev/null
  if [[ $status -ne 0 ]]; then
    for log in "$work"/*.log; do echo "== $log" >&2; tail -20 "$log" >&2; done
  fi
  exit $status
}
trap cleanup EXIT INT TERM

fail() {
  echo "$test_name: FAIL: $*" >&2
  exit 1
}

spawn() {
  local name=$1
  shift
  "$@" >"$work/$name.log" 2>&1 &
  spawned=$!
  started+=("$spawned")
}

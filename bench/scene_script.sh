# Sourced by the bench scripts that start a hub and a scene (fig9.sh, teleop_latency.sh).
#   private_namespace "$0" "$@"   as root, re-runs the calling script in a private mount
#                                 namespace (its own /tmp, /dev/shm and /run), so that its
#                                 hub cannot meet another
#   then: $work, a scratch folder, and $pids, the processes to stop, both cleaned on exit
#   (with every other job still running).

private_namespace() {
  if [[ $(id -u) == 0 && -z ${AFHUB_BENCH_PRIVATE:-} ]]; then
    # A clone under /tmp, ../shared beside it and paths given under /tmp stay visible.
    local root
    root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
    exec env AFHUB_BENCH_PRIVATE=1 AFHUB_SOURCE_ROOT="$root" unshare -m bash -c \
      'source "$AFHUB_SOURCE_ROOT/tests/support/private_tmp.sh" &&
       mount_private_tmp "$AFHUB_SOURCE_ROOT" "$AFHUB_SOURCE_ROOT/../shared" "$0" "$@" &&
       mount -t tmpfs tmpfs /dev/shm && mount -t tmpfs tmpfs /run && exec "$0" "$@"' \
      "$@"
  fi
  work=$(mktemp -d)
  pids=()
  trap cleanup EXIT
}

cleanup() {
  # Those named, and any other job still running: a script that fails midway (set -e)
  # may leave a paused physics, which the wait below would wait for forever.
  for pid in "${pids[@]}" $(jobs -p); do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}

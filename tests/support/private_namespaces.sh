#!/usr/bin/env bash
# Runs one test in mount and network namespaces of its own: /tmp, /dev/shm and
# /run/afhub are empty tmpfs, and the only interface is loopback. Its hub, its ports and
# its files meet no other test's and no user's hub (a demo left running, say), so hub
# tests run in parallel. Needs root (as `./run.sh test` is run).
#   private_namespaces.sh COMMAND [ARGS...]
set -euo pipefail
if [[ -z "${AFHUB_PRIVATE_NAMESPACES:-}" ]]; then
  if [[ $EUID -ne 0 ]]; then
    echo "private_namespaces.sh: the hub tests need root for their private namespaces" >&2
    exit 1
  fi
  exec env AFHUB_PRIVATE_NAMESPACES=1 unshare --mount --net --propagation private bash "$0" "$@"
fi
# A tree under /tmp (a clone there, its build, ../shared beside it) stays visible.
support=$(cd "$(dirname "$0")" && pwd)
source "$support/private_tmp.sh"
mount_private_tmp "$support/../.." "$support/../../../shared" "$1"
# Huge pages where a file is big enough: RouDi writes every page of its 150 MB of
# segments at start, and on this kind of VM 4 KiB page faults made that 8 to 10 s of a
# loaded machine (2 MiB pages: about half). A user's /dev/shm can be mounted so too.
mount -t tmpfs -o mode=1777,huge=within_size tmpfs /dev/shm
mkdir -p /run/afhub
mount -t tmpfs -o mode=0755 tmpfs /run/afhub
ip link set lo up
exec "$@"

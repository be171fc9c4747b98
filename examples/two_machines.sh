#!/usr/bin/env bash
# Two "machines" on this one host, joined by `afhub bridge dds`: a way to try the bridge
# without a second computer. Each machine is a network namespace with its own hub (its
# own /tmp, /dev/shm and /run), joined to the other by a virtual Ethernet link that
# carries the DDS traffic and nothing else.
#   machine A runs the example arm and a bridge that exports it and accepts commands;
#   machine B runs a bridge that mirrors A's bodies into B's hub;
# then COMMAND runs on B (by default an interactive shell), and everything is removed
# when it ends. Needs root (namespaces). Examples:
#   sudo examples/two_machines.sh                       # a shell on B; try `afhub ls`
#   sudo examples/two_machines.sh afhub ctl sine arm/base --amplitude 0.4
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
# $AFHUB, else the afhub of this source tree's build, else the one installed.
[[ -x $here/../build/release/bin/afhub ]] && PATH=$(realpath "$here/../build/release/bin"):$PATH
[[ -n ${AFHUB:-} ]] && PATH=$(dirname "$(realpath "$AFHUB")"):$PATH
afhub=$(command -v afhub) || {
  echo "two_machines.sh: no afhub: build it first (./run.sh build)" >&2
  exit 1
}
test_name=two_machines.sh
# The same set-up the bridge's tests use: on, spawn, stop, and the clean-up on exit.
source "$here/../tests/bridges/two_machines.sh"

echo "two_machines.sh: starting the two machines (logs in $work)" >&2
for side in a b; do
  spawn $side hub_$side "$afhub" hub
  wait_until 60 "machine $side's hub to start" on $side "$afhub" status
done
spawn a physics "$afhub" run "$here/models/arm7.yaml"
spawn a bridge_a "$afhub" bridge dds --export --insecure-accept-commands
spawn b bridge_b "$afhub" bridge dds --mirror
on b "$afhub" echo arm/base --count 1 --wait 30 >/dev/null || fail "B does not list A's arm"
echo "two_machines.sh: machine B has A's bodies; A's arm follows B's commands" >&2

if [[ $# -eq 0 ]]; then
  on b env PS1='machine-B$ ' bash --norc -i
else
  on b "$@"
fi

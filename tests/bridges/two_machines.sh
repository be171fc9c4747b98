# Two "machines" on one host, sourced by the DDS bridge tests and bench/dds_bridge.sh: network namespaces
# $ns_a and $ns_b joined by a veth pair, each side in its own mount namespace with a
# private /tmp, /dev/shm and /run, so each has its own hub. DDS stays on the veth
# (unicast peers, no multicast). Gives:
#   on SIDE COMMAND...          run COMMAND on that "machine" (a or b)
#   spawn SIDE NAME COMMAND...  in the background, logging to $work/NAME.log; sets
#                               $spawned, the command's own pid
#   stop PID                    SIGTERM and wait (a process that reports as it goes)
#   fail MESSAGE                exit 1, printing A's hub log and every log
#   $veth_a, $ns_a              A's interface and network namespace (for tc)
# and cleans everything up on exit. Set test_name before sourcing. Needs root.
if [[ $EUID -ne 0 ]]; then
  echo "$test_name: needs root for ip netns and mounts" >&2
  exit 1
fi

tag=$$
ns_a=afhubA$tag
ns_b=afhubB$tag
veth_a=afA$tag
veth_b=afB$tag
subnet=$((tag % 250))
ip_a=10.232.$subnet.1
ip_b=10.232.$subnet.2
work=$(mktemp -d /tmp/afhub-dds-test.XXXXXX)
declare -A holder     # side -> pid of the process holding its mount namespace
declare -a started=() # every background process, killed on exit

cleanup() {
  local status=$?
  set +e # clean up everything, whatever fails
  # (bash reports each process killed below as "Killed": noise after a success)
  [[ $status -eq 0 ]] && exec 2>/dev/null
  for pid in "${started[@]}"; do kill -9 "$pid" 2>/dev/null || true; done
  for ns in "$ns_a" "$ns_b"; do
    for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -9 "$pid" 2>/dev/null || true; done
  done
  for side in a b; do [[ -n "${holder[$side]:-}" ]] && kill -9 "${holder[$side]}" 2>/dev/null || true; done
  wait 2>/dev/null || true
  for ns in "$ns_a" "$ns_b"; do
    for _ in $(seq 50); do [[ -z "$(ip netns pids "$ns" 2>/dev/null)" ]] && break; sleep 0.1; done
  done
  ip netns del "$ns_a" 2>/dev/null || true
  ip netns del "$ns_b" 2>/dev/null || true
  ip link del "$veth_a" 2>/dev/null || true
  if [[ $status -ne 0 ]]; then
    for log in "$work"/*.log; do echo "== $log" >&2; tail -20 "$log" >&2; done
  fi
  rm -rf "$work"
  exit $status
}
trap cleanup EXIT INT TERM

fail() {
  echo "$test_name: FAIL: $*" >&2
  echo "== A's hub log" >&2
  on a tail -20 /run/afhub/hub.log >&2 || true
  exit 1
}

# wait_until SECONDS WHAT COMMAND...: runs COMMAND every 0.1 s until it succeeds, and
# fails naming WHAT when it has not within SECONDS (on a loaded machine, starting is slow).
wait_until() {
  local seconds=$1 what=$2
  shift 2
  for _ in $(seq $((seconds * 10))); do "$@" >/dev/null 2>&1 && return 0; sleep 0.1; done
  fail "$what: not within $seconds s"
}

ip netns add "$ns_a"
ip netns add "$ns_b"
ip link add "$veth_a" netns "$ns_a" type veth peer name "$veth_b" netns "$ns_b"
ip -n "$ns_a" addr add "$ip_a/24" dev "$veth_a"
ip -n "$ns_b" addr add "$ip_b/24" dev "$veth_b"
for ns in "$ns_a" "$ns_b"; do ip -n "$ns" link set lo up; done
ip -n "$ns_a" link set "$veth_a" up
ip -n "$ns_b" link set "$veth_b" up

# Cyclone on the veth alone: unicast discovery to both addresses.
cyclone_uri() {
  echo "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface name=\"$1\"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers><Peer address=\"$ip_a\"/><Peer address=\"$ip_b\"/></Peers></Discovery><Tracing><Verbosity>none</Verbosity></Tracing></Domain></CycloneDDS>"
}
declare -A uri=([a]="$(cyclone_uri "$veth_a")" [b]="$(cyclone_uri "$veth_b")")
declare -A netns=([a]=$ns_a [b]=$ns_b)

# Each side's private /tmp keeps the source tree, ../shared, $work and the sourcing
# script's arguments (the program, models) when they live under /tmp. Its private /run
# holds a mark once every mount is made: a command entering the side before that would
# meet the host's hub (a demo's, say) instead of its own: with a fixed 0.5 s wait,
# the likely cause of dds_two_machines hanging to its timeout beside a demo hub.
root_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
private_mark=/run/afhub-test-side-$tag
for side in a b; do
  ip netns exec "${netns[$side]}" unshare -m --propagation private bash -c \
    'source "$0" && mount_private_tmp "${@:2}" && mount -t tmpfs tmpfs /dev/shm &&
     mount -t tmpfs tmpfs /run && touch "$1" && exec sleep infinity' \
    "$root_dir/tests/support/private_tmp.sh" "$private_mark" "$root_dir" "$root_dir/../shared" \
    "$work" "$@" &
  holder[$side]=$!
done
for side in a b; do
  for _ in $(seq 300); do
    nsenter -t "${holder[$side]}" -m -- test -e "$private_mark" 2>/dev/null && break
    sleep 0.1
  done
  nsenter -t "${holder[$side]}" -m -- test -e "$private_mark" ||
    { echo "$test_name: side $side's private namespaces not made within 30 s" >&2; exit 1; }
done

on() {
  local side=$1
  shift
  nsenter -t "${holder[$side]}" -m -n -- env CYCLONEDDS_URI="${uri[$side]}" "$@"
}
spawn() {
  local side=$1 name=$2
  shift 2
  nsenter -t "${holder[$side]}" -m -n -- env CYCLONEDDS_URI="${uri[$side]}" "$@" \
    >"$work/$name.log" 2>&1 &
  spawned=$!
  started+=("$spawned")
}
stop() {
  kill -TERM "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
}

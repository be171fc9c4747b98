# Sourced by bench/dds_bridge.sh: two "machines" on one host, network namespaces A and
# B joined by a veth pair, each in its own mount namespace (private /tmp, /dev/shm,
# /run), so each runs its own hub. Cyclone DDS stays on the veth (unicast peers).
# Needs root. After two_machines_up:
#   on SIDE COMMAND...          runs COMMAND on that machine (a or b)
#   spawn SIDE NAME COMMAND...  in the background, logging to $work/NAME.log; sets $spawned
#   $veth_a, $ns_a              A's interface and network namespace (for tc)
# Everything is removed on exit.

two_machines_up() {
  local tag=$$
  ns_a=afbenchA$tag
  ns_b=afbenchB$tag
  veth_a=abA$tag
  veth_b=abB$tag
  local subnet=$((tag % 250))
  ip_a=10.232.$subnet.1
  ip_b=10.232.$subnet.2
  work=$(mktemp -d /tmp/afhub-dds-bench.XXXXXX)
  declare -gA holder=()
  started=()
  trap two_machines_down EXIT INT TERM
  ip netns add "$ns_a"
  ip netns add "$ns_b"
  ip link add "$veth_a" netns "$ns_a" type veth peer name "$veth_b" netns "$ns_b"
  ip -n "$ns_a" addr add "$ip_a/24" dev "$veth_a"
  ip -n "$ns_b" addr add "$ip_b/24" dev "$veth_b"
  local ns
  for ns in "$ns_a" "$ns_b"; do ip -n "$ns" link set lo up; done
  ip -n "$ns_a" link set "$veth_a" up
  ip -n "$ns_b" link set "$veth_b" up
  declare -gA uri=([a]="$(cyclone_uri "$veth_a")" [b]="$(cyclone_uri "$veth_b")")
  declare -gA netns=([a]=$ns_a [b]=$ns_b)
  local side
  for side in a b; do
    ip netns exec "${netns[$side]}" unshare -m --propagation private bash -c \
      'mount -t tmpfs tmpfs /tmp && mount -t tmpfs tmpfs /dev/shm && mount -t tmpfs tmpfs /run && exec sleep infinity' &
    holder[$side]=$!
  done
  sleep 0.5
}

two_machines_down() {
  local status=$?
  set +e
  local pid ns side
  for pid in "${started[@]}"; do kill -9 "$pid" 2>/dev/null; done
  for ns in "$ns_a" "$ns_b"; do
    for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -9 "$pid" 2>/dev/null; done
  done
  for side in a b; do [[ -n "${holder[$side]:-}" ]] && kill -9 "${holder[$side]}" 2>/dev/null; done
  wait 2>/dev/null
  for ns in "$ns_a" "$ns_b"; do
    for _ in $(seq 50); do [[ -z "$(ip netns pids "$ns" 2>/dev/null)" ]] && break; sleep 0.1; done
  done
  ip netns del "$ns_a" 2>/dev/null
  ip netns del "$ns_b" 2>/dev/null
  if [[ $status -ne 0 ]]; then
    for log in "$work"/*.log; do echo "== $log" >&2; tail -20 "$log" >&2; done
  fi
  rm -rf "$work"
  exit $status
}

cyclone_uri() {
  echo "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface name=\"$1\"/></Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>20</MaxAutoParticipantIndex><Peers><Peer address=\"$ip_a\"/><Peer address=\"$ip_b\"/></Peers></Discovery><Tracing><Verbosity>none</Verbosity></Tracing></Domain></CycloneDDS>"
}

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

# stop PID: SIGTERM and wait (a process that must report before it goes).
stop() {
  kill -TERM "$1" 2>/dev/null || true
  wait "$1" 2>/dev/null || true
}

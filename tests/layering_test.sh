#!/usr/bin/env bash
# The dependency rule of the folders (docs/architecture.md, "Layers"): shm_layout at
# the bottom; rt and rt/yaml (the located YAML reader) on shm_layout alone; hub/client
# on rt, hub/daemon on the client; the physics core on shm_layout, rt and rt/yaml;
# physics/channels and controllers on hub/client; bench on those; device_drivers on
# hub/client (not physics or controllers); record (MCAP) on hub/client; python on
# hub/client and rt; cli on everything. Fails, naming the file, when a layer includes one above it, or when the
# test binary of rt or of the physics core links iceoryx.
set -euo pipefail
source_dir=$1
physics_core_tests=$2
rt_tests=$3
status=0

# forbid FOLDER PATTERN...: no file under FOLDER includes a header matching PATTERN.
forbid() {
  local folder=$1
  shift
  for pattern in "$@"; do
    if grep -rnE "#include \"afhub/($pattern)/" "$source_dir/$folder"; then
      echo "layering: $folder/ must not include afhub/$pattern/ (a layer above it)" >&2
      status=1
    fi
  done
}

forbid shm_layout 'hub|rt|yaml|physics|controllers|devices|bench'
forbid hub 'physics|controllers|devices|bench'
forbid rt 'hub|physics|controllers|devices|bench'
forbid rt/yaml 'hub|rt|physics|controllers|devices|bench'
forbid physics/src 'hub|controllers|devices|bench'
forbid physics/include 'hub|controllers|devices|bench'
forbid physics/channels 'controllers|devices|bench'
forbid controllers 'physics|bench'
forbid device_drivers 'physics|controllers|bench'
forbid bench '(cli)'
forbid viewer 'physics|controllers|devices|bench'
forbid bridges 'physics|controllers|devices|bench|viewer'
forbid record 'physics|controllers|devices|bench|viewer|bridges'
forbid python 'physics|controllers|devices|bench|viewer'
if grep -rn '#include "afhub/hub/hub_daemon.hpp"' "$source_dir/hub/client"; then
  echo "layering: hub/client must not include the daemon" >&2
  status=1
fi
if grep -rn '#include "commands.hpp"\|#include "format.hpp"' "$source_dir"/{shm_layout,hub,rt,physics,controllers,device_drivers,bench}; then
  echo "layering: only cli/ includes the command line's headers" >&2
  status=1
fi

# no_iceoryx WHAT BINARY: BINARY (WHAT's tests, linking WHAT alone) has no iceoryx in it.
no_iceoryx() {
  if ldd "$2" | grep -i iceoryx; then
    echo "layering: $1's tests link iceoryx" >&2
    status=1
  fi
  if nm -C "$2" | grep "iox::" >/dev/null; then
    echo "layering: $1's tests contain iceoryx symbols" >&2
    status=1
  fi
}
no_iceoryx "the physics core" "$physics_core_tests"
no_iceoryx rt "$rt_tests"
exit $status

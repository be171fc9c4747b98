#!/usr/bin/env bash
# Runs the Python tests with a hub of their own, started before pytest and stopped after
# it has exited (a process still attached would see its hub vanish). Run it inside
# tests/support/private_namespaces.sh, as ctest does:
#   run_tests.sh AFHUB PYTHON [pytest arguments...]
set -euo pipefail
export AFHUB=$1 PYTHON=$2
shift 2
log=$(mktemp /tmp/afhub-python-hub.XXXXXX.log)
"$AFHUB" hub > "$log" 2>&1 &
for _ in $(seq 200); do
  "$AFHUB" status > /dev/null 2>&1 && break
  sleep 0.1
done
status=0
"$PYTHON" -m pytest -p no:cacheprovider -q -rs "$(dirname "$0")" "$@" || status=$?
"$AFHUB" hub stop --force > /dev/null 2>&1 || { echo "the hub did not stop:"; cat "$log"; }
wait
exit $status

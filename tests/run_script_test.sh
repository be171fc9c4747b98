#!/usr/bin/env bash
# run.sh's phases: when a phase fails while another runs in the background (the
# sanitizer build beside the tests), the script exits with the failure and leaves
# nothing of the background phase running, its children included (a build's
# compilers once went on for minutes after a failed `./run.sh test`).
set -uo pipefail
source_dir=$1
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
marker="$scratch/still-running"

# A script made of run.sh's phase functions: a background phase whose child sleeps,
# then a phase that fails.
cat > "$scratch/phases.sh" <<SCRIPT
set -euo pipefail
eval "\$(sed -n '/^# phase NAME/,/^trap print_phases EXIT/p' "$source_dir/run.sh")"
slow() { bash -c 'sleep 60; touch "$marker"'; }
background_phase slow "$scratch/slow.log" slow
sleep 0.5
phase failing false
SCRIPT
bash "$scratch/phases.sh" > "$scratch/out.log" 2>&1
status=$?
if [ $status -eq 0 ]; then
  echo "FAIL: the script exited 0 after a failed phase"
  exit 1
fi
# What the background phase started, were it still there: its sleep of 60 s.
sleep 0.5
for pid in /proc/[0-9]*; do
  if tr '\0' ' ' < "$pid/cmdline" 2>/dev/null | grep -qF "$marker"; then
    echo "FAIL: the background phase's child ${pid#/proc/} still runs after the script exited"
    kill "${pid#/proc/}" 2>/dev/null
    exit 1
  fi
done
echo "ok: exit $status, nothing of the background phase left running"

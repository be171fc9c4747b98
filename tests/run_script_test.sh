#!/usr/bin/env bash
# run.sh's phases: when a phase fails while another runs in the background, the script
# exits with the failure and
#   - ends a stoppable background phase (the sanitizer build beside the tests) with
#     what it started (a build's compilers once went on for minutes after a failed
#     `./run.sh test`);
#   - waits for any other (the test packages' install: dpkg or npm ended midway would
#     leave the machine's packages or node_modules half done).
set -uo pipefail
source_dir=$1
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT
status=0

# run_phases STOPPABLE JOB: a script of run.sh's phase functions that starts JOB (a
# command line that touches $scratch/started first) as a background phase, then fails
# a phase. Exits the test if run.sh's functions were not taken, or the script did not
# fail.
run_phases() {
  cat > "$scratch/phases.sh" <<SCRIPT
set -euo pipefail
eval "\$(sed -n '/^# phase NAME/,/^trap print_phases EXIT/p' "$source_dir/run.sh")"
declare -F phase background_phase print_phases > /dev/null
job() { bash -c '$2'; }
background_phase $1 job "$scratch/job.log" job
sleep 0.5
phase failing false
SCRIPT
  rm -f "$scratch/started"
  (cd "$scratch" && bash phases.sh > out.log 2>&1)  # whatever it writes, it writes there
  local exit_code=$?
  # The job touches "started" first: without it, run.sh's functions were not taken.
  if [ $exit_code -eq 0 ] || [ ! -e "$scratch/started" ]; then
    echo "FAIL: the phases did not run as run.sh's (exit $exit_code):"
    cat "$scratch/out.log"
    exit 1
  fi
}

# A stoppable phase: its child, asleep for a minute, is gone when the script has exited.
marker="$scratch/stoppable-child"
run_phases --stoppable "touch $scratch/started; sleep 60; touch $marker"
sleep 0.5
for pid in /proc/[0-9]*; do
  if { tr "\\0" " " < "$pid/cmdline"; } 2> /dev/null | grep -qF "$marker"; then
    echo "FAIL: the stoppable phase's child ${pid#/proc/} still runs after the script exited"
    kill "${pid#/proc/}" 2> /dev/null
    status=1
  fi
done

# Any other: it has finished by the time the script has exited.
finished="$scratch/finished"
run_phases "" "touch $scratch/started; sleep 1; touch $finished"
if [ ! -e "$finished" ]; then
  echo "FAIL: the script exited before its background install-like phase finished"
  status=1
fi

[ $status -eq 0 ] && echo "ok: a failed phase ends a stoppable background phase, waits for others"
exit $status

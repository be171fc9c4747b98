#!/usr/bin/env bash
# `afhub bridge dds --config FILE` from the command line: the file's settings, the
# flags given over them (--check prints what the bridge would run with), and a bad
# file refused with its line, a non-zero exit and no bridge started.
# Usage: dds_config_cli_test.sh AFHUB_BINARY
set -euo pipefail
afhub=$(realpath "$1")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() {
  echo "dds_config_cli_test: FAIL: $*" >&2
  exit 1
}

cat >"$work/bridge.yaml" <<'YAML'
domain: 3
export: true
insecure-accept-commands: true
bodies: ["afhub/arm/*"]
devices: falcon*
world: true
qos: reliable
rate-limits: {bodies: 200, world: 50}
max-command-age: 0.02
YAML

# The file alone.
out=$("$afhub" bridge dds --config "$work/bridge.yaml" --check)
for line in 'domain: 3' 'export: true' 'accept-commands: true' 'insecure-accept-commands: true' 'bodies: ["afhub/arm/*"]' \
  'devices: ["falcon*"]' 'world: true' 'qos: reliable' 'spin: false' \
  'rate-limits: {bodies: 200, devices: 0, world: 50}' 'max-command-age: 0.02'; do
  grep -qxF "$line" <<<"$out" || fail "the file's '$line' is not in the settings:
$out"
done
if grep -q cpu-wake-latency <<<"$out"; then fail "cpu-wake-latency set with no one asking"; fi

# Flags override the file; what neither sets keeps its default.
out=$("$afhub" bridge dds --config "$work/bridge.yaml" --check --domain 5 --best-effort \
  --bodies 'ambf/env/*' --world-rate 10 --max-command-age 0.1 --spin --cpu-wake-latency 0)
for line in 'domain: 5' 'qos: best-effort' 'bodies: ["ambf/env/*"]' 'spin: true' 'cpu-wake-latency: 0' \
  'rate-limits: {bodies: 200, devices: 0, world: 10}' 'max-command-age: 0.1' \
  'export: true' 'mirror: false' 'rate: 1000'; do
  grep -qxF "$line" <<<"$out" || fail "'$line' is not in the settings with flags:
$out"
done

# expect_refused FILE_TEXT MESSAGE: the bridge refuses the file, naming MESSAGE.
expect_refused() {
  printf '%s\n' "$1" >"$work/bad.yaml"
  local status=0
  "$afhub" bridge dds --config "$work/bad.yaml" >"$work/out" 2>"$work/err" || status=$?
  [[ $status -ne 0 ]] || fail "a bad config was accepted: $1"
  grep -qF "$work/bad.yaml:$2" "$work/err" || fail "expected '$2' for '$1', got: $(cat "$work/err")"
}
expect_refused $'export: true\nmirorr: true' "2:1: error: unknown key 'mirorr'; the keys are domain,"
expect_refused $'export: true\nqos: fastest' "2:6: error: 'qos' must be best-effort or reliable"
expect_refused 'domain: 999' "1:9: error: 'domain' is 999; write a value from 0 to 232"
expect_refused $'export: true\nrate-limits: {bodies: fast}' "2:23: error: 'rate-limits: bodies' must be a number"

if "$afhub" bridge dds --export --cpu-wake-latency 5000 --check >/dev/null 2>"$work/err"; then
  fail "--cpu-wake-latency 5000 was accepted"
fi
grep -qF -- "--cpu-wake-latency must be 0 to 1000 microseconds" "$work/err" ||
  fail "unexpected message: $(cat "$work/err")"

# Settings that are each fine but wrong together are refused by --check too.
printf 'world: true\nexport: true\nmirror: true\n' >"$work/both.yaml"
if "$afhub" bridge dds --config "$work/both.yaml" --check >/dev/null 2>"$work/err"; then
  fail "--world with --export and --mirror was accepted"
fi
grep -q "a hub has one world" "$work/err" || fail "unexpected message: $(cat "$work/err")"
# Commands from the network without --security only when asked for by name.
if "$afhub" bridge dds --export --accept-commands --check >/dev/null 2>"$work/err"; then
  fail "--accept-commands without --security was accepted"
fi
grep -q "lets any host on DDS domain 0 command.*--insecure-accept-commands" "$work/err" ||
  fail "unexpected message: $(cat "$work/err")"
printf 'export: true\naccept-commands: true\n' >"$work/open.yaml"
if "$afhub" bridge dds --config "$work/open.yaml" --check >/dev/null 2>"$work/err"; then
  fail "a config's accept-commands without security was accepted"
fi
out=$("$afhub" bridge dds --export --insecure-accept-commands --check)
for line in 'accept-commands: true' 'insecure-accept-commands: true'; do
  grep -qxF "$line" <<<"$out" || fail "'$line' is not in the settings of --insecure-accept-commands:
$out"
done
echo "dds_config_cli_test: PASS"

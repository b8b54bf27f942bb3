#!/usr/bin/env bash
# The README's test command on a machine without the real data (a user's machine): the realdata tests skip with a
# message and the run passes, reporting how many were skipped; under CI=true the same absence is an error.
# Runs the realdata label only (the other labels never read $ROTOLIDAR_DATA). Needs a built build/.
set -euo pipefail
cd "$(dirname "$0")/.."
missing=$(mktemp -d)/no-such-data
log=$(mktemp)
trap 'rm -f "$log"' EXIT

echo "[missing-data] without CI: realdata tests must skip and the test command must pass"
if ! env -u CI ROTOLIDAR_DATA="$missing" bash .ci/setup.sh test -L realdata > "$log" 2>&1; then
  cat "$log"; echo "[missing-data] FAILED: the test command failed without the data"; exit 1
fi
grep -q ' 0 tests failed out of ' "$log" || { cat "$log"; echo "[missing-data] FAILED: a realdata test failed"; exit 1; }
skipped=$(sed -n "s|^\[setup\] real data: $missing does not exist; \([0-9]*\) tests skipped.*|\1|p" "$log")
[ -n "$skipped" ] && [ "$skipped" -gt 0 ] || {
  cat "$log"; echo "[missing-data] FAILED: the run did not report its skipped realdata tests"; exit 1; }
grep -m1 '\[realdata\] skipped:' "$log" || { echo "[missing-data] FAILED: no skip message"; exit 1; }
echo "[missing-data] ok: $skipped realdata tests skipped with a message, exit 0"

echo "[missing-data] with CI=true: the same absence must fail"
if CI=true ROTOLIDAR_DATA="$missing" bash .ci/setup.sh test -L realdata > "$log" 2>&1; then
  cat "$log"; echo "[missing-data] FAILED: CI=true passed without the data"; exit 1
fi
grep -m1 'CI=true: real data is required' "$log" || { cat "$log"; echo "[missing-data] FAILED: no CI message"; exit 1; }
echo "[missing-data] ok: CI=true without the data fails"

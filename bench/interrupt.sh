#!/usr/bin/env bash
# Sends SIGTERM to dpts-par SECONDS into a run on DEM and reports how it ended: exit code,
# how long it took to stop, its last message, and what it left in the output folder.
#   bench/interrupt.sh DEM SECONDS [dpts-par options...]     (needs build/dpts-par)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dem=$1 seconds=$2
shift 2
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$root/build/dpts-par" "$@" "$dem" "$out/out.ply" 2>"$out/.stderr" &
pid=$!
sleep "$seconds"
kill -TERM $pid
t0=$(date +%s.%N)
rc=0
wait $pid || rc=$?
t1=$(date +%s.%N)
echo "dpts-par $* $(basename "$dem"): SIGTERM after $seconds s; exit $rc, stopped $(echo "$t1 - $t0" | bc) s later"
echo "  progress then: $(grep -v -e interrupted -e '^$' "$out/.stderr" | tail -n 1)"
echo "  message: $(tail -n 1 "$out/.stderr")"
echo "  files left in the output folder: $(ls -A "$out" | grep -vc '^.stderr$' || true)"

#!/usr/bin/env bash
# Runs dpts-par with ARGS, sends it SIGTERM after SECONDS, and reports how it ended: exit
# code, how long it took to stop, its last progress line and message, and the temporary
# files left in OUT_DIR (where ARGS write).
#   bench/interrupt.sh SECONDS OUT_DIR dpts-par-arguments...      (needs build/dpts-par)
# e.g. bench/interrupt.sh 25 /tmp/x --algo vp-meta ../shared/data/olympic_srtm1_n48w125.tif /tmp/x/out.ply
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
seconds=$1 out=$2
shift 2
mkdir -p "$out"
err=$(mktemp)
trap 'rm -f "$err"' EXIT
"$root/build/dpts-par" "$@" 2>"$err" &
pid=$!
sleep "$seconds"
kill -TERM $pid
t0=$(date +%s.%N)
rc=0
wait $pid || rc=$?
t1=$(date +%s.%N)
echo "dpts-par $*: SIGTERM after $seconds s; exit $rc, stopped $(echo "$t1 - $t0" | bc) s later"
echo "  progress then: $(grep -v -e interrupted -e '^$' "$err" | tail -n 1)"
echo "  message: $(tail -n 1 "$err")"
echo "  temporary files left in $out: $(find "$out" -name '*.partial*' | wc -l)"
echo "  outputs in $out: $(find "$out" -name '*.ply' | wc -l)"

#!/usr/bin/env bash
# Issue 7's figures: a batch over every DEM of a folder plus two broken files, resumed; then
# the same batch killed by SIGTERM mid-way and run again, its outputs compared (sha256) with
# those of the uninterrupted batch.
#   bench/batch_check.sh [DATA_DIR] [KILL_AFTER_S] [dpts-par options...]
# defaults: ../shared/data, 20 s, --algo vp-meta. Needs build/dpts-par.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
data=${1:-$root/../shared/data}
kill_after=${2:-20}
shift 2 || shift $# || true
options=("$@")
[ ${#options[@]} -eq 0 ] && options=(--algo vp-meta)
exe=$root/build/dpts-par
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir "$work/in"
for f in "$data"/*.tif; do ln -s "$(cd "$(dirname "$f")" && pwd)/$(basename "$f")" "$work/in/"; done
# Two broken inputs: a download cut short, and text under a raster's name.
first=$(ls "$data"/*.tif | head -n 1)
head -c "$(( $(stat -c %s "$first") / 2 ))" "$first" >"$work/in/zz_truncated.tif"
echo "not a DEM" >"$work/in/zz_text.tif"
echo "inputs: $(ls "$work/in" | wc -l) ($(ls "$data"/*.tif | wc -l) DEMs of $data, 2 broken); options: ${options[*]}"

run() {  # $1: out dir; the rest: extra arguments. Prints wall seconds, keeps the exit code.
  local out=$1; shift
  local t0 t1 rc=0
  t0=$(date +%s.%N)
  "$exe" --batch "$work/in" --out-dir "$work/$out" "${options[@]}" "$@" 2>"$work/$out.log" || rc=$?
  t1=$(date +%s.%N)
  echo "$(echo "$t1 - $t0" | bc) $rc"
}
summary() {
  python3 -c 'import json,sys; s=json.load(open(sys.argv[1])); print("  ok %d, skipped %d, failed %d, interrupted %d, not run %d, batch wall %.2f s" % (s["ok"], s["skipped"], s["failed"], s["interrupted_inputs"], s["not_run"], s["wall_s"])); [print("  %s: %s" % (f["status"], f["error"])) for f in s["failures"]]' "$1/batch-summary.json"
}

read -r wall rc <<<"$(run whole)"
echo "first run: $wall s, exit $rc"
summary "$work/whole"
read -r wall rc <<<"$(run whole)"
echo "second run (resume): $wall s, exit $rc"
summary "$work/whole"

# Killed mid-way, then run again.
"$root/bench/interrupt.sh" "$kill_after" "$work/killed" \
  --batch "$work/in" --out-dir "$work/killed" "${options[@]}"
summary "$work/killed"
read -r wall rc <<<"$(run killed)"
echo "re-run: $wall s, exit $rc"
summary "$work/killed"
same=0 differ=0
for f in "$work/whole"/*.ply; do
  if [ "$(sha256sum <"$f")" = "$(sha256sum <"$work/killed/$(basename "$f")")" ]; then
    same=$((same + 1))
  else
    differ=$((differ + 1))
  fi
done
echo "outputs identical (sha256) to the uninterrupted batch: $same of $((same + differ))"
[ $differ -eq 0 ]

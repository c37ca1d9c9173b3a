#!/usr/bin/env bash
# End-to-end timing of the evaluator: simplifies DEM to 10 % with dpts-par, then runs the full
# measure (100 points x 3 sets, T and T') with dpts-eval at --threads 1 and 2, printing CSV:
# threads,wall_s,max_rss_kb,bytes_per_cell,distance_error and the speedup.
# Usage: bench/eval_timing.sh DEM [extra dpts-eval options, e.g. --delta 20]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dem=${1:?usage: eval_timing.sh DEM [dpts-eval options]}
shift
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$root/build/dpts-par" --quiet --keep 10% "$dem" "$tmp/t10.ply"
cells=$(gdalinfo "$dem" | awk '/^Size is/ {gsub(",", ""); print $3 * $4}')
echo "threads,wall_s,max_rss_kb,bytes_per_cell,distance_error"
declare -A wall
for t in 1 2; do
  /usr/bin/time -f "%e %M" -o "$tmp/time" "$root/build/dpts-eval" --quiet --json --threads "$t" \
    --dem "$dem" --mesh "$tmp/t10.ply" "$@" > "$tmp/json"
  read -r w rss < "$tmp/time"
  err=$(sed -n 's/.*"distance_error":\([^,]*\),.*/\1/p' "$tmp/json")
  wall[$t]=$w
  echo "$t,$w,$rss,$(awk -v r="$rss" -v c="$cells" 'BEGIN {printf "%.0f", r * 1024 / c}'),$err"
done
awk -v a="${wall[1]}" -v b="${wall[2]}" 'BEGIN {printf "# speedup threads 2 over 1: %.2f\n", a / b}'

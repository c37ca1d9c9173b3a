#!/usr/bin/env bash
# Scaling of the piece engine: runs dpts-par --algo vp-meta (or the --algo given) on DEM at
# --threads 1, 2, 4, ... up to the core count (or MAX_THREADS), RUNS times each, and prints CSV:
#   threads,run,wall_s,peak_rss_kb,rss_before_merge_kb,kept_kb,sha256,count_s,values_s,simplify_s,
#   merge_s,write_s,pieces,longest_piece_s,mean_piece_s
# then, per thread count, the median wall time, the speedup over 1 thread, and the critical
# path bound (longest piece against the mean: the speedup no core count can beat on the
# simplify stage is pieces x mean / longest).
# Usage: bench/scaling.sh DEM [RUNS=3] [MAX_THREADS=nproc] [dpts-par options...]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dem=${1:?usage: scaling.sh DEM [RUNS] [MAX_THREADS] [dpts-par options]}
runs=${2:-3}
max=${3:-$(nproc)}
shift $(($# < 3 ? $# : 3))
opts=("$@")
[[ " ${opts[*]} " == *" --algo "* ]] || opts=(--algo vp-meta "${opts[@]}")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# shellcheck source=bench/timing.sh
source "$root/bench/timing.sh"
mapfile -t threads < <(thread_counts "$max")
echo "threads,run,wall_s,peak_rss_kb,rss_before_merge_kb,kept_kb,sha256,count_s,values_s,simplify_s,merge_s,write_s,pieces,longest_piece_s,mean_piece_s"
for ((run = 1; run <= runs; ++run)); do
  for t in "${threads[@]}"; do
    /usr/bin/time -f "%e %M" -o "$tmp/time" "$root/build/dpts-par" --verbose --threads "$t" \
      "${opts[@]}" "$dem" "$tmp/out.ply" 2> "$tmp/log"
    read -r wall rss < "$tmp/time"
    hash=$(sha256sum "$tmp/out.ply" | cut -c1-16)
    awk -v t="$t" -v run="$run" -v wall="$wall" -v rss="$rss" -v hash="$hash" '
      /stages: count/ { gsub(",", ""); count = $4; values = $7; simplify = $10; merge = $13 }
      /stages: write/ { write = $4 }
      /pieces \(blocks/ { pieces = $2 }
      /pieces: longest/ { gsub(",", ""); longest = $4; mean = $7; kept = $(NF - 1) * 1024
                          for (i = 1; i < NF; ++i) if ($i == "merge") before = $(i + 1) * 1024 }
      END { printf "%s,%s,%s,%s,%.0f,%.0f,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", t, run, wall, rss, before,
            kept, hash, count, values, simplify, merge, write, pieces, longest, mean }' "$tmp/log"
  done
done | tee "$tmp/csv"
# Medians per thread count (sorted numerically by hand: mawk has no asort).
for t in "${threads[@]}"; do
  med=$(awk -F, -v t="$t" '$1 == t { print $3 }' "$tmp/csv" | sort -n |
    awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }')
  awk -F, -v t="$t" -v med="$med" '$1 == t { p = $13; l += $14; m += $15; n++ }
    END { printf "%s %s %d %.4f %.4f\n", t, med, p, l / n, m / n }' "$tmp/csv"
done | awk '
  NR == 1 { base = $2 }
  { printf "# threads %s: median wall %.2f s, speedup over 1 thread %.2f; %d pieces, longest/mean piece %.2f (simplify-stage speedup bound %.1f)\n",
      $1, $2, base / $2, $3, $4 / $5, $3 * $5 / $4 }'

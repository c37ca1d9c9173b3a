#!/usr/bin/env bash
# Scaling as users benchmark it: dpts-par (default mode, or the options given) on three sizes of
# one DEM (as given, and resampled to 1/2 and 1/4 of its cell size with gdalwarp -r cubic:
# 4 x and 16 x the cells) at --threads 1, 2, 4, ... up to the core count (or MAX_THREADS).
# Prints CSV, medians over RUNS:
#   cells,threads,wall_s,cpu_s,us_per_cell,peak_rss_mb,speedup
# and draws scaling.png (or PNG=...): speedup against threads per size, and CPU us per cell
# against cells per thread count (gnuplot; Debian gnuplot-nox).
# After each size, a comment line says whether every thread count wrote the same bytes.
# FROM_CSV=FILE draws the PNG from that CSV (this script's output, comment lines allowed) and runs
# nothing: for a CSV measured on a machine without gnuplot.
# Usage: [RUNS=1] [MAX_THREADS=nproc] [PNG=scaling.png] bench/scaling_sizes.sh DEM [dpts-par options]
#        FROM_CSV=FILE [PNG=scaling.png] bench/scaling_sizes.sh [TITLE]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${DPTS_BUILD:-$root/build}
png=${PNG:-scaling.png}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# shellcheck source=bench/timing.sh
source "$root/bench/timing.sh"
if [[ -n ${FROM_CSV:-} ]]; then
  grep -v '^#' "$FROM_CSV" > "$tmp/csv"
  mapfile -t threads < <(awk -F, 'NR > 1 {print $2}' "$tmp/csv" | sort -n | uniq)
  cores=$(awk -F, 'NR > 1 && $2 > m {m = $2} END {print m}' "$tmp/csv")
  title=${1:-}
else
  dem=${1:?usage: scaling_sizes.sh DEM [dpts-par options]}
  shift
  runs=${RUNS:-1}
  max=${MAX_THREADS:-$(nproc)}
  cores=$(nproc)
  title="$*"
  mapfile -t threads < <(thread_counts "$max")
  res=$(raster_cell_size "$dem")
  inputs=("$dem")
  for f in 2 4; do
    gdalwarp -q -r cubic -tr "$(awk -v r="$res" -v f="$f" 'BEGIN {print r / f}')" \
      "$(awk -v r="$res" -v f="$f" 'BEGIN {print r / f}')" "$dem" "$tmp/x$f.tif"
    inputs+=("$tmp/x$f.tif")
  done

  echo "# $dem and 2 resampled sizes; ${runs} run(s) each; $(nproc) cores; dpts-par $*"
  echo "cells,threads,wall_s,cpu_s,us_per_cell,peak_rss_mb,speedup" | tee "$tmp/csv"
  for input in "${inputs[@]}"; do
    cells=$(raster_cells "$input")
    base=
    : > "$tmp/hashes"
    for t in "${threads[@]}"; do
      timed "$build/dpts-par" --quiet --threads "$t" "$@" "$input" "$tmp/out.ply"
      base=${base:-$wall}
      timed_row "$cells" "$t" "$cells" "$base" | tee -a "$tmp/csv"
      sha256sum < "$tmp/out.ply" | cut -c1-16 >> "$tmp/hashes"
    done
    if [[ $(sort -u "$tmp/hashes" | wc -l) == 1 ]]; then
      echo "# $cells cells: the same output bytes at every thread count ($(head -1 "$tmp/hashes"))"
    else
      echo "# $cells cells: OUTPUTS DIFFER between thread counts: $(tr '\n' ' ' < "$tmp/hashes")"
    fi
  done
fi

if ! command -v gnuplot > /dev/null; then
  echo "# no gnuplot (apt-get install gnuplot-nox): $png not drawn" >&2
  exit 0
fi
# One data block per size (speedup panel) and per thread count (us/cell panel).
awk -F, 'NR > 1 && $1 != last {if (NR > 2) print "\n"; last = $1} NR > 1 {print $2, $7, $1}' \
  "$tmp/csv" > "$tmp/by_size.dat"
for t in "${threads[@]}"; do
  awk -F, -v t="$t" 'NR > 1 && $2 == t {print $1, $5}' "$tmp/csv"
  printf '\n\n'
done > "$tmp/by_threads.dat"
sizes=$(awk -F, 'NR > 1 {print $1}' "$tmp/csv" | uniq | tr '\n' ' ')
gnuplot <<EOF
set terminal pngcairo size 1200,500 font ",11"
set output "$png"
set multiplot layout 1,2 title "dpts-par${title:+ $title}: scaling ($cores cores)"
set key top left
set grid
set title "wall-time speedup over 1 thread"
set xlabel "threads"
set ylabel "speedup"
sizes = "$sizes"
plot for [i=0:2] "$tmp/by_size.dat" index i using 1:2 with linespoints lw 2 \
  title sprintf("%.2fM cells", word(sizes, i + 1) / 1e6), x with lines dt 2 lc "gray" title "ideal"
set title "CPU time per input cell"
set xlabel "input cells"
set ylabel "us per cell (CPU)"
set logscale x
set yrange [0:*]
threads = "${threads[*]}"
plot for [i=0:${#threads[@]}-1] "$tmp/by_threads.dat" index i using 1:2 with linespoints lw 2 \
  title sprintf("%s thread(s)", word(threads, i + 1))
unset multiplot
EOF
echo "# drawn: $png"

#!/usr/bin/env bash
# Speed of each mode, as users time it: simplifies DEM to KEEP with dpts-par at --threads 1
# and 2, RUNS times each, and prints CSV (medians over the runs):
#   tool,threads,wall_s,cpu_s,us_per_cell,peak_rss_mb,speedup
# us_per_cell is CPU time (user + system) per input cell; speedup is the 1-thread wall time over
# this one. With HMM=/path/to/hmm (fogleman/hmm, greedy insertion, built outside this repo:
# README, "Tests and benchmarks") the same figures for hmm on the same DEM and vertex count,
# in the same run. DPTS_BUILD: another build folder (default build/), e.g. a "before" build.
# Usage: [MODES="qem vp"] [RUNS=3] [HMM=...] bench/speed_table.sh DEM [KEEP=10]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${DPTS_BUILD:-$root/build}
dem=${1:?usage: speed_table.sh DEM [KEEP percent]}
keep=${2:-10}
runs=${RUNS:-3}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# shellcheck source=bench/timing.sh
source "$root/bench/timing.sh"
cells=$(raster_cells "$dem")
echo "# $dem: $cells cells, keep $keep %, $runs runs, $(nproc) cores"
echo "tool,threads,wall_s,cpu_s,us_per_cell,peak_rss_mb,speedup"

for mode in ${MODES:-qem vp vp-meta pld-meta qslim}; do
  base=
  for t in 1 2; do
    timed "$build/dpts-par" --quiet --threads "$t" --algo "$mode" --keep "$keep%" "$dem" \
      "$tmp/$mode.ply"
    base=${base:-$wall}
    timed_row "dpts $mode" "$t" "$cells" "$base"
  done
done

if [[ -n "${HMM:-}" ]]; then
  # hmm reads a 16-bit grey PNG: heights scaled to 0-65535, z scale = height range in cells.
  read -r lo hi < <(gdalinfo -mm "$dem" | awk -F'[=,]' '/Computed Min\/Max/ {print $2, $3}')
  cell=$(raster_cell_size "$dem")
  gdal_translate -q -ot UInt16 -scale "$lo" "$hi" 0 65535 -of PNG "$dem" "$tmp/dem.png"
  zscale=$(awk -v lo="$lo" -v hi="$hi" -v c="$cell" 'BEGIN {print (hi - lo) / c}')
  points=$((cells * keep / 100))
  timed "$HMM" -q -z "$zscale" -p "$points" -e 0 "$tmp/dem.png" "$tmp/hmm.stl"
  timed_row "hmm" 1 "$cells" "$wall"
fi

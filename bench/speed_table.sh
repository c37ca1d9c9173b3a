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
read -r width height < <(gdalinfo "$dem" | awk '/^Size is/ {gsub(",", ""); print $3, $4}')
cells=$((width * height))
echo "# $dem: $cells cells, keep $keep %, $runs runs, $(nproc) cores"
echo "tool,threads,wall_s,cpu_s,us_per_cell,peak_rss_mb,speedup"

median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }

# Runs "$@" RUNS times under /usr/bin/time; sets wall, cpu, rss (medians).
timed() {
  : > "$tmp/times"
  for ((r = 0; r < runs; ++r)); do
    /usr/bin/time -f "%e %U %S %M" -o "$tmp/time" "$@" > /dev/null
    cat "$tmp/time" >> "$tmp/times"
  done
  wall=$(awk '{print $1}' "$tmp/times" | median)
  cpu=$(awk '{print $2 + $3}' "$tmp/times" | median)
  rss=$(awk '{print $4}' "$tmp/times" | median)
}

row() {  # tool threads base_wall
  awk -v tool="$1" -v t="$2" -v w="$wall" -v c="$cpu" -v r="$rss" -v n="$cells" -v base="$3" \
    'BEGIN {printf "%s,%d,%.2f,%.2f,%.2f,%.0f,%.2f\n", tool, t, w, c, c * 1e6 / n, r / 1024, base / w}'
}

for mode in ${MODES:-qem vp vp-meta pld-meta qslim}; do
  base=
  for t in 1 2; do
    timed "$build/dpts-par" --quiet --threads "$t" --algo "$mode" --keep "$keep%" "$dem" \
      "$tmp/$mode.ply"
    base=${base:-$wall}
    row "dpts $mode" "$t" "$base"
  done
done

if [[ -n "${HMM:-}" ]]; then
  # hmm reads a 16-bit grey PNG: heights scaled to 0-65535, z scale = height range in cells.
  read -r lo hi < <(gdalinfo -mm "$dem" | awk -F'[=,]' '/Computed Min\/Max/ {print $2, $3}')
  cell=$(gdalinfo "$dem" | awk -F'[(,)]' '/^Pixel Size/ {print ($2 < 0 ? -$2 : $2)}')
  gdal_translate -q -ot UInt16 -scale "$lo" "$hi" 0 65535 -of PNG "$dem" "$tmp/dem.png"
  zscale=$(awk -v lo="$lo" -v hi="$hi" -v c="$cell" 'BEGIN {print (hi - lo) / c}')
  points=$((cells * keep / 100))
  timed "$HMM" -q -z "$zscale" -p "$points" -e 0 "$tmp/dem.png" "$tmp/hmm.stl"
  row "hmm" 1 "$wall"
fi

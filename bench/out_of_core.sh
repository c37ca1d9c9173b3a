#!/usr/bin/env bash
# Out-of-core figures, as the user runs it: dpts-par --threads 2 --tile-mb 256 (or the options
# given) on a DEM resampled to 1/F of its cell size for each F in FACTORS (gdalwarp -r cubic;
# default "5 10": San Gabriel's 30 m cells to 6 m, 19M cells, and to 3 m, 77M). Prints CSV:
#   cells,wall_s,cpu_s,wall_us_per_cell,peak_rss_mb,budget_mb
# (budget: threads x tile-mb + 256 MB, the flat-memory target), then the wall per cell of the
# largest over the smallest and the difference of their peaks. With MPI=N (and dpts-mpi
# built), each size also runs under mpirun -np N (--threads 1 per rank) and its output is
# compared with dpts-par's, byte for byte.
# Usage: [FACTORS="5 10"] [MPI=2] bench/out_of_core.sh DEM [dpts-par options]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${DPTS_BUILD:-$root/build}
dem=${1:?usage: out_of_core.sh DEM [dpts-par options]}
shift
opts=("$@")
((${#opts[@]})) || opts=(--threads 2 --tile-mb 256)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
runs=1
# shellcheck source=bench/timing.sh
source "$root/bench/timing.sh"
threads=2 tile=256
for ((i = 0; i < ${#opts[@]} - 1; ++i)); do
  [[ ${opts[i]} == --threads ]] && threads=${opts[i + 1]}
  [[ ${opts[i]} == --tile-mb ]] && tile=${opts[i + 1]}
done
budget=$((threads * tile + 256))
res=$(raster_cell_size "$dem")
echo "# $dem resampled by ${FACTORS:-5 10}; dpts-par ${opts[*]}; $(nproc) cores"
echo "cells,wall_s,cpu_s,wall_us_per_cell,peak_rss_mb,budget_mb"
first=
for f in ${FACTORS:-5 10}; do
  r=$(awk -v r="$res" -v f="$f" 'BEGIN {print r / f}')
  gdalwarp -q -r cubic -tr "$r" "$r" -co TILED=YES -co COMPRESS=DEFLATE "$dem" "$tmp/in.tif"
  cells=$(raster_cells "$tmp/in.tif")
  timed "$build/dpts-par" --quiet "${opts[@]}" "$tmp/in.tif" "$tmp/par.ply"
  per=$(awk -v w="$wall" -v n="$cells" 'BEGIN {printf "%.3f", w * 1e6 / n}')
  mb=$(awk -v r="$rss" 'BEGIN {printf "%.0f", r / 1024}')
  echo "$cells,$wall,$cpu,$per,$mb,$budget"
  [[ -n $first ]] || first="$per $mb"
  last="$per $mb"
  if [[ -n ${MPI:-} ]]; then
    /usr/bin/time -f "%e" -o "$tmp/mpi_time" mpirun -q -np "$MPI" --oversubscribe \
      "$build/dpts-mpi" --quiet "${opts[@]}" --threads 1 "$tmp/in.tif" "$tmp/mpi.ply"
    same=$(cmp -s "$tmp/par.ply" "$tmp/mpi.ply" && echo "identical" || echo "DIFFERENT")
    echo "# mpirun -np $MPI dpts-mpi --threads 1: $(cat "$tmp/mpi_time") s wall, output $same"
  fi
  rm -f "$tmp/in.tif"
done
read -r p0 m0 <<< "$first"
read -r p1 m1 <<< "$last"
awk -v a="$p0" -v b="$p1" -v ma="$m0" -v mb="$m1" 'BEGIN {
  printf "# wall per cell, largest / smallest: %.2f (target <= 1.3); peak RSS difference: %+d MB (target <= 100)\n", b / a, mb - ma}'

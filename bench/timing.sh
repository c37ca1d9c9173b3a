# Shared by the bench scripts that time whole runs (sourced, not run): speed_table.sh,
# scaling_sizes.sh, scaling.sh and out_of_core.sh. Callers of timed set `tmp` (a scratch
# folder) and `runs` first.

# The median of the numbers on stdin, one a line (mawk has no asort: sorted by sort -g).
median() {
  sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'
}

# Runs "$@" `runs` times under /usr/bin/time, its stdout discarded; sets wall, cpu (user +
# system seconds) and rss (peak, KB): medians over the runs.
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

# Thread counts 1, 2, 4, ... below $1, then $1 itself, one a line.
thread_counts() {
  local t
  for ((t = 1; t < $1; t *= 2)); do echo "$t"; done
  echo "$1"
}

# The raster's cell count, and its cell size (absolute x pixel size), by gdalinfo.
raster_cells() { gdalinfo "$1" | awk '/^Size is/ {gsub(",", ""); print $3 * $4}'; }
raster_cell_size() { gdalinfo "$1" | awk -F'[(,)]' '/^Pixel Size/ {print ($2 < 0 ? -$2 : $2)}'; }

# One CSV row from timed's figures: label, threads, us/cell over `cells`, speedup over `base`
# wall seconds: label,threads,wall_s,cpu_s,us_per_cell,peak_rss_mb,speedup
timed_row() {  # label threads cells base_wall
  awk -v label="$1" -v t="$2" -v n="$3" -v base="$4" -v w="$wall" -v c="$cpu" -v r="$rss" \
    'BEGIN {printf "%s,%d,%.2f,%.2f,%.2f,%.0f,%.2f\n", label, t, w, c, c * 1e6 / n, r / 1024, base / w}'
}

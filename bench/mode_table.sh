#!/usr/bin/env bash
# Distance error and vertical RMSE of each simplification mode at each size, on one DEM: for
# each mode and keep, simplifies with dpts-par and measures with dpts-eval (its default, near
# exact measure, or the options given, e.g. --exact), printing CSV:
# dem,mode,keep,vertices,distance_error,rmse_m,max_m,coverage
# DPTS_BUILD: another build folder (default build/).
# Usage: bench/mode_table.sh DEM [dpts-eval options; default --points 60 --sets 3]
#   MODES="qslim qem" KEEPS="10 30 50 70" bench/mode_table.sh ../shared/data/st_helens_crater.tif
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${DPTS_BUILD:-$root/build}
dem=${1:?usage: mode_table.sh DEM [dpts-eval options]}
shift
[ $# -gt 0 ] || set -- --points 60 --sets 3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
name=$(basename "$dem")
echo "dem,mode,keep,vertices,distance_error,rmse_m,max_m,coverage"
for mode in ${MODES:-vp vp-meta qslim qem}; do
  for keep in ${KEEPS:-10 30 50 70}; do
    "$build/dpts-par" --quiet --algo "$mode" --keep "$keep%" "$dem" "$tmp/s.ply"
    "$build/dpts-eval" --quiet --json "$@" --dem "$dem" --mesh "$tmp/s.ply" > "$tmp/e.json"
    python3 - "$tmp/e.json" "$name" "$mode" "$keep" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
print(f'{sys.argv[2]},{sys.argv[3]},{sys.argv[4]},{r["mesh_vertices"]},{r["distance_error"]:.6g},'
      f'{r["vertical_rmse"]:.4f},{r["vertical_max"]:.4f},{r["coverage"]:.9f}')
PY
  done
done

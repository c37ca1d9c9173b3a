#!/bin/sh
# The C++ package as a user meets it: install the build, build examples/cmake-consumer against
# the installed dpts (find_package), run it on the sample DEM. Usage: package_test.sh BUILD SRC
set -eu
build=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cmake --install "$build" --prefix "$tmp/prefix" > "$tmp/install.log"
cmake -S "$src/examples/cmake-consumer" -B "$tmp/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/configure.log"
cmake --build "$tmp/build" > "$tmp/build.log"
"$tmp/build/consumer" "$src/data/olinda_dem_utm25s.tif" "$tmp/out.ply" | tee "$tmp/run.log"
grep -q "^dpts 0\.1\.0: 12321 -> 1232 vertices" "$tmp/run.log"
grep -q "^distance error 0\.[0-9]*, vertical RMSE" "$tmp/run.log"
grep -q "^a stopped call throws: interrupted" "$tmp/run.log"
# The library's mesh is dpts-par's.
"$build/dpts-par" --quiet "$src/data/olinda_dem_utm25s.tif" "$tmp/par.ply"
body() { echo $(( $(grep -abo end_header "$1" | head -1 | cut -d: -f1) + 11 )); }
cmp -i "$(body "$tmp/out.ply"):$(body "$tmp/par.ply")" "$tmp/out.ply" "$tmp/par.ply"
echo "package test: ok"

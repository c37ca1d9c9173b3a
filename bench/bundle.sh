#!/usr/bin/env bash
# The tools with the Debian 12 libraries they load, for timing them on a machine that has none
# of them (a lent many-core machine: no GDAL, no TBB, another distribution). Packs build/'s
# dpts-par and dpts-eval, gdalinfo, gdalwarp and /usr/bin/time, every shared library they load
# (ldd) with the loader itself, PROJ's and GDAL's data, and the DEMs given, into one .tar.xz.
# There: unpack it into a folder B and `source B/env.sh`: bin/ then holds wrappers that run
# each tool under the packed loader and libraries, first on PATH, and /usr/bin/time is put in
# place if missing (root only). Then, e.g.:
#   DPTS_BUILD=B/bin bench/scaling_sizes.sh B/dem/san_gabriel_bigtujunga_utm11.tif
# (gnuplot is not packed: draw the plot here from the CSV, scaling_sizes.sh's FROM_CSV=).
# San Gabriel with the tools: about 46 MB.
# Usage: [DPTS_BUILD=build] bench/bundle.sh OUT.tar.xz [DEM ...]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${DPTS_BUILD:-$root/build}
out=${1:?usage: bundle.sh OUT.tar.xz [DEM ...]}
shift
case $out in /*) ;; *) out=$PWD/$out ;; esac
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/real" "$tmp/libs" "$tmp/bin" "$tmp/share" "$tmp/dem"
tools=("$build/dpts-par" "$build/dpts-eval" "$(command -v gdalinfo)" "$(command -v gdalwarp)"
  /usr/bin/time)
for t in "${tools[@]}"; do
  [[ -x $t ]] || { echo "bundle.sh: $t: not found (build first; apt-get install gdal-bin time)" >&2; exit 1; }
  cp -L "$t" "$tmp/real/"
  # The libraries (name => path) and the loader (a bare path).
  ldd "$t" | awk '$2 == "=>" && $3 ~ /^\// {print $3} $1 ~ /^\// {print $1}'
done | sort -u | while read -r lib; do cp -L "$lib" "$tmp/libs/"; done
loader=$(basename "$(ldd "$build/dpts-par" | awk '$1 ~ /^\// {print $1; exit}')")
cp /usr/share/proj/proj.db "$tmp/share/"
cp -r /usr/share/gdal "$tmp/share/gdal"
for dem in "$@"; do cp -L "$dem" "$tmp/dem/"; done
for t in "${tools[@]}"; do
  name=$(basename "$t")
  cat > "$tmp/bin/$name" <<EOF
#!/bin/sh
d=\$(cd "\$(dirname "\$(readlink -f "\$0")")/.." && pwd)
exec "\$d/libs/$loader" --library-path "\$d/libs" "\$d/real/$name" "\$@"
EOF
  chmod +x "$tmp/bin/$name"
done
cat > "$tmp/env.sh" <<'EOF'
# Sourced on the other machine: the packed tools first on PATH, with their data.
bundle=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export PATH="$bundle/bin:$PATH" PROJ_DATA="$bundle/share" PROJ_LIB="$bundle/share" \
  GDAL_DATA="$bundle/share/gdal"
if [ ! -x /usr/bin/time ] && [ "$(id -u)" = 0 ]; then
  printf '#!/bin/sh\nexec "%s/bin/time" "$@"\n' "$bundle" > /usr/bin/time
  chmod +x /usr/bin/time
fi
EOF
tar -C "$tmp" -cf - . | xz -T2 -6 > "$out"
echo "bundle.sh: $out ($(du -h "$out" | cut -f1)): $(ls "$tmp/libs" | wc -l) libraries, $# DEM(s)"

#!/usr/bin/env bash
# Prepares data/olinda_dem_utm25s.tif, the sample DEM of the README, from Debian's
# r-cran-stars package (apt-get download + dpkg -x): nothing third-party is committed.
# Provenance and licence: data/README.md. Idempotent: does nothing when the file exists.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
out="$here/olinda_dem_utm25s.tif"
[[ -s $out ]] && exit 0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# apt-get download needs package lists; fetch them only when the package is unknown.
if ! apt-cache show r-cran-stars >/dev/null 2>&1; then
  apt-get update -qq
fi
(cd "$tmp" && apt-get download -qq r-cran-stars 2>/dev/null) ||
  { echo "prepare_sample.sh: apt-get download r-cran-stars failed" >&2; exit 1; }
dpkg -x "$tmp"/r-cran-stars_*.deb "$tmp/pkg"
src=$(find "$tmp/pkg" -name olinda_dem_utm25s.tif | head -n 1)
[[ -n $src ]] || { echo "prepare_sample.sh: olinda_dem_utm25s.tif not found in r-cran-stars" >&2; exit 1; }
cp "$src" "$out.tmp" && mv "$out.tmp" "$out"
echo "data/olinda_dem_utm25s.tif prepared from $(basename "$tmp"/r-cran-stars_*.deb)"

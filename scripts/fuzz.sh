#!/usr/bin/env bash
# Builds the libFuzzer harnesses with clang (ASan + UBSan) in build-fuzz/ and runs each one:
#   scripts/fuzz.sh [SECONDS] [ply|raster ...]     default: 600 s each, both harnesses
# ply_fuzz: the PLY reader and dpts-eval's mesh path; raster_fuzz: GDAL raster -> open_dem ->
# whole-DEM VP and the meta engine. Seeds are made here (PLY variants, crops of the sample DEM,
# structured raster descriptions); corpora grow in build-fuzz/corpus-*/, crashes land in
# build-fuzz/crashes/. Prints executions and CPU time per harness; exit 1 on a crash.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
seconds=${1:-600}
shift || true
harnesses=("$@")
[ ${#harnesses[@]} -eq 0 ] && harnesses=(ply raster)
out=$root/build-fuzz
if ! command -v clang++ >/dev/null || [ ! -e /usr/lib/llvm-14/lib/clang/14.0.6/lib/linux/libclang_rt.fuzzer-x86_64.a ]; then
  sudo_cmd=$([ "$(id -u)" = 0 ] && echo "" || echo sudo)
  $sudo_cmd apt-get install -y -q clang libclang-rt-14-dev >/dev/null
fi
san="-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
cmake -S "$root" -B "$out" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_CXX_FLAGS="$san" \
  -DDPTS_BUILD_TESTS=OFF -DDPTS_BUILD_BENCH=OFF -DDPTS_BUILD_FUZZ=ON >/dev/null
ninja -C "$out" -j "${JOBS:-2}" ply_fuzz raster_fuzz

seeds() {  # $1: harness, $2: folder
  mkdir -p "$2"
  case "$1" in
    ply)
      local head='ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n'
      printf "${head}0 0 0\n4 0 1\n4 4 2\n0 4 1\n3 0 1 2\n3 0 2 3\n" >"$2/square.ply"
      printf "${head}0 0 0\n4 0 1\n4 4 2\n0 4 1\n3 0 2 1\n3 0 2 3\n" >"$2/folded.ply"
      printf "${head}0 0 0\n2 0 1\n4 0 2\n0 4 1\n3 0 1 2\n3 0 2 3\n" >"$2/flat.ply"
      printf 'ply\nformat ascii 1.0\ncomment x\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar uint vertex_index\nproperty int flags\nend_header\n0 0 0 9\n1 0 0 9\n0 1 0 9\n3 0 1 2 7\n' >"$2/extra.ply"
      # Binary: the square as dpts-par writes it, little and big endian.
      python3 - "$2" <<'PY'
import struct, sys
v = [(0, 0, 0), (4, 0, 1), (4, 4, 2), (0, 4, 1)]
f = [(0, 1, 2), (0, 2, 3)]
for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
    h = ("ply\nformat %s 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
         "property double z\nelement face 2\nproperty list uchar int vertex_indices\n"
         "end_header\n" % fmt).encode()
    body = b"".join(struct.pack(e + "ddd", *p) for p in v)
    body += b"".join(struct.pack(e + "Biii", 3, *t) for t in f)
    open("%s/%s.ply" % (sys.argv[1], fmt), "wb").write(h + body)
PY
      ;;
    raster)
      local dem=$root/data/olinda_dem_utm25s.tif
      gdal_translate -q -srcwin 100 100 12 10 "$dem" "$2/crop.tif"
      gdal_translate -q -srcwin 0 0 16 16 -ot Int16 -a_nodata 0 "$dem" "$2/corner_int16.tif"
      gdal_translate -q -srcwin 40 40 8 8 -a_srs EPSG:4326 -a_ullr -35 -8 -34.99 -8.01 "$dem" "$2/geographic.tif"
      rm -f "$2"/*.aux.xml
      # Structured: width-1, height-1, type index, flags, 8 bytes no-data, then cells.
      python3 - "$2" <<'PY'
import math, struct, sys
for name, w, h, t, flags in (("f32", 6, 5, 5, 0b0010010), ("i16_void", 5, 5, 2, 0b1010000),
                             ("rotated", 6, 6, 6, 0b0010110), ("geo", 5, 4, 5, 0b0100000)):
    cells = [100 + 10 * math.sin(i) for i in range(w * h)]
    pack = {5: "<f", 6: "<d", 2: "<h"}[t]
    body = b"".join(struct.pack(pack, int(c) if t == 2 else c) for c in cells)
    open("%s/%s.bin" % (sys.argv[1], name), "wb").write(
        bytes([w - 1, h - 1, t, flags]) + struct.pack("<d", -9999.0) + body)
PY
      ;;
  esac
}

status=0
mkdir -p "$out/crashes"
for h in "${harnesses[@]}"; do
  corpus=$out/corpus-$h
  seeds "$h" "$corpus"
  log=$out/fuzz-$h.log
  echo "fuzz: $h for $seconds s (corpus $corpus, log $log)"
  set +e
  /usr/bin/time -f "%U %S" -o "$out/time-$h" "$out/${h}_fuzz" "$corpus" \
    -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=30 -print_final_stats=1 \
    -artifact_prefix="$out/crashes/$h-" >"$log" 2>&1
  rc=$?
  set -e
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  cpu=$(tail -n 1 "$out/time-$h" | awk '{printf "%.1f", ($1 + $2) / 60}')
  echo "fuzz: $h: $execs executions, $cpu CPU minutes, exit $rc, corpus $(ls "$corpus" | wc -l) files"
  if [ $rc -ne 0 ]; then
    status=1
    grep -m 5 -E 'ERROR|SUMMARY|terminate|what\(\)' "$log" || true
  fi
done
exit $status

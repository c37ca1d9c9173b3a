#!/usr/bin/env python3
"""Writes four small synthetic DEMs (120 x 120 cells, EPSG:32611 GeoTIFFs) into a folder, for
checking dpts-eval against exact geodesics on surfaces unlike the shared DEMs
(bench/eval_accuracy.sh):

  terraces.tif  20 m steps every 15 cells along a slanted line, 0-0.5 m of noise (10 m cells)
  rough.tif     +-15 m of white noise on a gentle slope: saddles everywhere (10 m cells)
  volcano.tif   a smooth cone with a crater and a 150 m deep, 4-cell-wide canyon (30 m cells)
  lakes.tif     smooth hills with two no-data lakes (10 m cells)

The same files on every run (seeded). Needs gdal_translate (gdal-bin).
Usage: bench/synthetic_dems.py OUT_DIR
"""
import math
import os
import random
import subprocess
import sys


def write(folder, name, n, height, cell=10.0, nodata=None):
    asc = os.path.join(folder, name + ".asc")
    with open(asc, "w") as out:
        out.write(f"ncols {n}\nnrows {n}\nxllcorner 500000\nyllcorner 4000000\ncellsize {cell}\n")
        if nodata is not None:
            out.write(f"NODATA_value {nodata}\n")
        # Rows from north to south, as the ASCII grid format has them.
        for r in range(n):
            out.write(" ".join("%.3f" % height(c, r) for c in range(n)) + "\n")
    tif = os.path.join(folder, name + ".tif")
    subprocess.run(["gdal_translate", "-q", "-a_srs", "EPSG:32611", asc, tif], check=True)
    os.remove(asc)
    print(tif)


def volcano(c, r):
    x, y = c - 60, r - 60
    d = math.hypot(x, y)
    h = 400 * math.exp(-((d / 35) ** 2)) - 250 * math.exp(-((d / 10) ** 2))
    if abs(x - 0.3 * y - 20) < 2 and y > 0:
        h -= 150
    return h


def lakes(c, r):
    if (c - 40) ** 2 + (r - 50) ** 2 < 150 or (c - 85) ** 2 + (r - 80) ** 2 < 100:
        return -9999
    return 100 * math.sin(c / 9) * math.cos(r / 13) + 0.3 * r


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: synthetic_dems.py OUT_DIR")
    folder = sys.argv[1]
    os.makedirs(folder, exist_ok=True)
    random.seed(7)
    write(folder, "terraces", 120,
          lambda c, r: 20 * math.floor((c + 0.4 * r) / 15) + random.uniform(0, 0.5))
    write(folder, "rough", 120, lambda c, r: 0.5 * c + random.uniform(-15, 15))
    write(folder, "volcano", 120, volcano, cell=30.0)
    write(folder, "lakes", 120, lakes, nodata=-9999)


if __name__ == "__main__":
    main()

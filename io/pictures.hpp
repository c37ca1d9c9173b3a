// Pictures of a TIN against its DEM, as PNG: the vertical error per cell, and the two surfaces'
// hillshades side by side. Drawn on a raster canvas with a built-in 5 x 7 font (labels, colour
// bar, scale bar), hillshades by GDALDEMProcessing, encoded by GDAL's PNG driver.
#pragma once

#include <array>
#include <string>
#include <vector>

namespace dpts::io {

// Values on the DEM's cells (row-major, as the DEM's rows and columns), NaN where none.
struct CellRaster {
  int width = 0, height = 0;
  std::vector<float> values;
  double cell_x_m = 1, cell_y_m = 1;  // a cell's size in metres (hillshade, scale bar)
};

// The vertical error map as PNG bytes: TIN height minus DEM height at each cell, on a
// diverging ramp (blue: TIN below the DEM, white: 0, red: above) saturating at a round limit
// at or above the 99th percentile of |error|, with a colour bar, its labels, a scale bar and
// the RMSE and maximum. A raster over 1000 cells on a side is shrunk (each pixel shows its
// block's largest |error|); one under 400 is enlarged. Cells without a value are grey.
// Throws IoError when GDAL cannot encode it.
std::string error_map_png(const CellRaster& error);

// The DEM's and the TIN's hillshades (GDAL's: sun from the north-west, 45 degrees up) side by
// side as PNG bytes, labelled, with a scale bar; `edges` (grid positions c0, r0, c1, r1 of
// each edge; cell centres at whole numbers), if not empty, drawn over the TIN's.
std::string hillshade_compare_png(const CellRaster& dem, const CellRaster& tin,
                                  const std::string& tin_label,
                                  const std::vector<std::array<double, 4>>& edges);

}  // namespace dpts::io

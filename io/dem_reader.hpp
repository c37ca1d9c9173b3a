// Reading a DEM (band 1 of any raster GDAL opens) into a height grid, with its CRS handling.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/elimination.hpp"
#include "core/grid.hpp"

class OGRCoordinateTransformation;

namespace dpts::io {

struct DemReadOptions {
  // Output CRS as GDAL understands it (EPSG:32633, a WKT, a PROJ string). Empty: keep a
  // projected CRS as it is, and project a geographic one to the UTM zone of the DEM's centre.
  std::string t_srs;
};

struct TransformDeleter {
  void operator()(OGRCoordinateTransformation* t) const;
};

// A DEM in memory: heights (NaN = no-data) and the geometry of its cells.
struct Dem {
  std::string path;
  core::HeightGrid grid;
  core::GridFrame frame;           // metric frame of the grid (see core/grid.hpp)
  std::string output_wkt;          // CRS of the output coordinates; empty if the DEM has none
  std::string output_crs_name;     // short name for messages
  std::vector<std::string> notes;  // what the user should know (CRS choices, warnings)
  std::size_t valid_cells = 0;
  double metres_per_output_unit = 1.0;
  double geotransform[6] = {0, 1, 0, 0, 0, -1};
  std::unique_ptr<OGRCoordinateTransformation, TransformDeleter> to_output;  // null: identity

  // Cell centres of the given cells (row-major indices) in the output CRS: x0, y0, x1, ...
  // Throws IoError if the CRS transformation fails.
  std::vector<double> output_xy(const std::vector<std::uint32_t>& cells) const;

  // Grid positions (col, row; cell centres at integers) of points given in the output CRS:
  // the inverse of output_xy. Throws IoError if the CRS transformation fails.
  std::vector<double> grid_xy(const std::vector<double>& output_xy) const;

  std::unique_ptr<OGRCoordinateTransformation, TransformDeleter> from_output;  // null: identity

  // For a reprojected DEM (to_output set): a thread-safe test for core's outline rule. It
  // accepts the straight outline chord from cell a to cell b when the exact projection of the
  // outline cell halfway between them lies within tolerance_m of the chord (the grid line is
  // a smooth curve in the output CRS, farthest from its chord near the middle). Null for a DEM
  // whose frame is exact. Precomputes the output positions of all outline cells.
  std::function<bool(std::uint32_t, std::uint32_t)> outline_chord_test(double tolerance_m) const;
};

// Reads band 1 of `path`. No-data cells, NaN and infinite heights become NaN. Checks the
// raster before reading it and throws InputError naming the file (not a raster, no band,
// degenerate geotransform, too large), or UsageError for a bad --t-srs. Calls progress with
// stage "read". GDALAllRegister() must have been called.
Dem read_dem(const std::string& path, const DemReadOptions& options,
             const core::Progress& progress);

}  // namespace dpts::io

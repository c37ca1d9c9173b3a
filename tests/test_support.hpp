// Helpers shared by the tests: hand-made grids, temporary folders, running executables.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/elimination.hpp"
#include "core/grid.hpp"

namespace dpts::test {

// A width x height grid with z = f(col, row); f returning NaN makes a no-data cell.
core::HeightGrid make_grid(int width, int height, const std::function<double(int, int)>& f);

// A fresh, empty temporary folder, removed with its contents when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
  std::vector<std::string> files() const;  // names of the entries, sorted

 private:
  std::filesystem::path path_;
};

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

// Runs an executable with arguments (no shell), capturing stdout and stderr.
RunResult run(const std::string& exe, const std::vector<std::string>& args);

// Writes a single-band GeoTIFF (Float32, or Int16 when int16 is true) of the grid; NaN
// cells get the nodata value. geotransform and wkt as GDAL takes them (wkt may be empty).
void write_geotiff(const std::filesystem::path& path, const core::HeightGrid& grid,
                   const std::vector<double>& geotransform, const std::string& wkt,
                   double nodata = -9999.0);

// Grid positions (col, row) of a TIN's vertices, for footprint checks.
std::vector<double> grid_xy(const core::HeightGrid& grid, const core::Tin& tin);

// Frame positions of a TIN's vertices (cells of grid g).
std::vector<double> frame_xy(const core::HeightGrid& g, const core::GridFrame& f,
                             const core::Tin& tin);

// Number of interior edges whose opposite vertex lies strictly inside the circumcircle.
std::size_t non_delaunay_edges(const std::vector<double>& xy, const core::Tin& tin);

// Checks (Catch2 CHECKs) every structural property of a simplified TIN over grid g:
// counter-clockwise faces, proper edges, area = the footprint's, no face over no-data,
// Delaunay, cells sorted, every vertex used.
void check_tin(const core::HeightGrid& g, const core::Tin& tin, const core::GridFrame& f = {});

// The shared real-DEM folder (../shared/data).
std::string shared_data(const std::string& name);

}  // namespace dpts::test

// The in-memory raster source (see raster_source.hpp).
#include "core/raster_source.hpp"

#include <stdexcept>

namespace dpts::core {

MemoryRaster::MemoryRaster(HeightGrid grid, const GridFrame& frame, std::string name)
    : RasterSource(std::move(name), grid.width, grid.height, frame), grid_(std::move(grid)) {
  if (grid_.width < 0 || grid_.height < 0 ||
      grid_.z.size() != static_cast<std::size_t>(grid_.width) * grid_.height) {
    throw std::invalid_argument("MemoryRaster: the grid's size does not match its heights");
  }
}

HeightGrid MemoryRaster::read(int col0, int row0, int width, int height, Implausible*) const {
  if (col0 < 0 || row0 < 0 || width < 0 || height < 0 || col0 + width > grid_.width ||
      row0 + height > grid_.height) {
    throw std::out_of_range(name() + ": window outside the raster");
  }
  HeightGrid g;
  g.width = width;
  g.height = height;
  g.z.resize(static_cast<std::size_t>(width) * height);
  for (int r = 0; r < height; ++r) {
    const auto from = grid_.z.begin() + static_cast<std::ptrdiff_t>(grid_.index(col0, row0 + r));
    std::copy(from, from + width, g.z.begin() + static_cast<std::ptrdiff_t>(g.index(0, r)));
  }
  return g;
}

std::vector<double> MemoryRaster::output_xy_of_grid(const std::vector<double>& grid_xy) const {
  const GridFrame& f = frame();
  std::vector<double> xy(grid_xy.size());
  for (std::size_t i = 0; 2 * i + 1 < grid_xy.size(); ++i) {
    const double c = grid_xy[2 * i], r = grid_xy[2 * i + 1];
    xy[2 * i] = (f.m[0][0] * c + f.m[0][1] * r) * f.metres_per_unit;
    xy[2 * i + 1] = (f.m[1][0] * c + f.m[1][1] * r) * f.metres_per_unit;
  }
  return xy;
}

std::function<bool(double, double, double&, double&)> MemoryRaster::grid_of_output_fn() const {
  const GridFrame f = frame();
  double inv[2][2];
  f.inverse(inv);
  return [f, a = inv[0][0], b = inv[0][1], c = inv[1][0], d = inv[1][1]](double x, double y,
                                                                         double& col, double& row) {
    const double u = x / f.metres_per_unit, w = y / f.metres_per_unit;
    col = a * u + b * w;
    row = c * u + d * w;
    return true;
  };
}

void MemoryRaster::frame_mesh_to_output(TriMesh& mesh) const {
  for (double& v : mesh.xyz) v *= frame().metres_per_unit;
}

}  // namespace dpts::core

// Real-DEM crops, and the accuracy of Steiner distances against exact geodesics (core/).
#include "support/exact_geodesic.hpp"

#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/exact_geodesic.hpp"
#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"

namespace dpts::test {

std::vector<double> exact_geodesics(const core::TriMesh& mesh, const core::SurfacePoint& source,
                                    const std::vector<core::SurfacePoint>& targets) {
  return core::ExactGeodesics(mesh).distances(source, targets);
}

core::TriMesh dem_crop(const std::string& path, int c0, int r0, int size) {
  GDALAllRegister();
  const io::Dem dem = io::read_dem(path, {}, nullptr);
  core::HeightGrid crop;
  crop.width = crop.height = size;
  for (int r = 0; r < size; ++r) {
    for (int c = 0; c < size; ++c) {
      const double z = dem.grid.z[dem.grid.index(c0 + c, r0 + r)];
      if (std::isnan(z)) throw std::runtime_error(path + ": crop has no-data");
      crop.z.push_back(z);
    }
  }
  const core::Tin grid = core::grid_tin(crop);
  core::TriMesh mesh;
  const double s = dem.frame.metres_per_unit;
  for (std::uint32_t cell : grid.cells) {
    const int c = static_cast<int>(cell % size), r = static_cast<int>(cell / size);
    mesh.xyz.insert(mesh.xyz.end(), {s * dem.frame.u(c, r), s * dem.frame.w(c, r), crop.z[cell]});
  }
  mesh.faces = grid.faces;
  core::fix_orientation(mesh);
  return mesh;
}

AccuracyFigures steiner_accuracy(const core::TriMesh& mesh, double delta, int sources, int targets,
                                 std::uint64_t seed) {
  const auto src = core::sample_uniform(mesh, static_cast<std::size_t>(sources), seed);
  const auto dst = core::sample_uniform(mesh, static_cast<std::size_t>(targets), seed + 1000);
  const core::SteinerGraph graph(mesh, delta);
  core::GeodesicQuery query(graph);
  const core::ExactGeodesics exact_geodesics(mesh);
  AccuracyFigures fig;
  fig.min_rel = 1e300;
  std::vector<double> steiner;
  double sum = 0;
  for (const auto& s : src) {
    const auto exact = exact_geodesics.distances(s, dst);
    query.distances(s, dst, steiner);
    for (std::size_t j = 0; j < dst.size(); ++j) {
      if (exact[j] <= 0) continue;
      const double rel = (steiner[j] - exact[j]) / exact[j];
      sum += rel;
      fig.max_rel = std::max(fig.max_rel, rel);
      fig.min_rel = std::min(fig.min_rel, rel);
      ++fig.pairs;
    }
  }
  fig.mean_rel = fig.pairs ? sum / fig.pairs : 0;
  return fig;
}

}  // namespace dpts::test

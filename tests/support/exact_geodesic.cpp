// Exact geodesics with CGAL's Surface_mesh_shortest_path, and the Steiner accuracy check.
#include "support/exact_geodesic.hpp"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_shortest_path.h>
#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"

namespace dpts::test {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using Traits = CGAL::Surface_mesh_shortest_path_traits<K, Mesh>;
using ShortestPath = CGAL::Surface_mesh_shortest_path<Traits>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<Mesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
}  // namespace

std::vector<double> exact_geodesics(const core::TriMesh& tin, const core::SurfacePoint& source,
                                    const std::vector<core::SurfacePoint>& targets) {
  Mesh mesh;
  std::vector<Mesh::Vertex_index> vs;
  for (std::size_t v = 0; v < tin.vertex_count(); ++v) {
    vs.push_back(
        mesh.add_vertex(K::Point_3(tin.xyz[3 * v], tin.xyz[3 * v + 1], tin.xyz[3 * v + 2])));
  }
  for (const auto& f : tin.faces) mesh.add_face(vs[f[0]], vs[f[1]], vs[f[2]]);
  ShortestPath sp(mesh);
  Tree tree;
  sp.build_aabb_tree(tree);
  sp.add_source_point(sp.locate(K::Point_3(source.x, source.y, source.z), tree));
  std::vector<double> out;
  for (const auto& t : targets) {
    const auto loc = sp.locate(K::Point_3(t.x, t.y, t.z), tree);
    out.push_back(sp.shortest_distance_to_source_points(loc.first, loc.second).first);
  }
  return out;
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
  const core::GridTin grid = core::grid_tin(crop);
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
  AccuracyFigures fig;
  fig.min_rel = 1e300;
  std::vector<double> steiner;
  double sum = 0;
  for (const auto& s : src) {
    const auto exact = exact_geodesics(mesh, s, dst);
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

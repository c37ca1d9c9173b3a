// Exact geodesics (CGAL's Surface_mesh_shortest_path) on hand-made TINs with known distances.
#include "core/exact_geodesic.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

#include "core/surface_sampling.hpp"

using namespace dpts;

namespace {

// Unit squares (col, row) of a grid, each split along one diagonal, at (x0 + col, y0 + row)
// and height z(x, y); vertices shared. Faces counter-clockwise.
core::TriMesh squares(const std::vector<std::pair<int, int>>& cells, double x0, double y0,
                      double (*z)(double, double)) {
  core::TriMesh m;
  std::map<std::pair<int, int>, std::uint32_t> index;
  auto vertex = [&](int c, int r) {
    const auto [it, added] = index.emplace(std::make_pair(c, r), index.size());
    if (added) m.xyz.insert(m.xyz.end(), {x0 + c, y0 + r, z(c, r)});
    return it->second;
  };
  for (const auto& [c, r] : cells) {
    const auto a = vertex(c, r), b = vertex(c + 1, r), d = vertex(c + 1, r + 1);
    const auto s = vertex(c, r + 1);
    m.faces.push_back({a, b, d});
    m.faces.push_back({a, d, s});
  }
  return m;
}

double flat(double, double) { return 0.0; }
double tilted(double x, double y) { return 0.3 * x - 0.2 * y; }

// A point of mesh m at (x, y), located and lifted as dpts-eval does.
core::SurfacePoint at(const core::TriMesh& m, double x, double y) {
  const auto hit = core::PointLocator(m).locate(x, y);
  REQUIRE(hit.has_value());
  return hit->point;
}

}  // namespace

TEST_CASE("exact geodesics on a plane are straight lines, at UTM coordinates too",
          "[core][exact]") {
  for (double x0 : {0.0, 562193.7312}) {
    CAPTURE(x0);
    const double y0 = x0 > 0 ? 5119847.2163 : 0.0;
    std::vector<std::pair<int, int>> cells;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 5; ++c) cells.emplace_back(c, r);
    }
    const auto m = squares(cells, x0, y0, tilted);
    const core::ExactGeodesics exact(m);
    CHECK(exact.face_count() == 40);
    // Sources and targets inside faces, on edges and on vertices.
    const auto src = at(m, x0 + 0.3, y0 + 0.4);
    const std::vector<core::SurfacePoint> targets = {
        at(m, x0 + 4.7, y0 + 3.1), at(m, x0 + 2.5, y0 + 2.5), at(m, x0 + 3, y0 + 1),
        at(m, x0 + 5, y0 + 4), at(m, x0 + 0.3, y0 + 0.4)};
    const auto d = exact.distances(src, targets);
    REQUIRE(d.size() == targets.size());
    for (std::size_t j = 0; j < targets.size(); ++j) {
      CAPTURE(j);
      const double dx = targets[j].x - src.x, dy = targets[j].y - src.y,
                   dz = targets[j].z - src.z;
      CHECK(d[j] == Approx(std::sqrt(dx * dx + dy * dy + dz * dz)).margin(1e-6));
    }
  }
}

TEST_CASE("exact geodesics bend around a reflex corner of the outline", "[core][exact]") {
  // An L of three unit squares: from (1.9, 0.9) to (0.9, 1.9) the straight line leaves the
  // surface; the shortest path turns at the corner (1, 1).
  const auto m = squares({{0, 0}, {1, 0}, {0, 1}}, 0, 0, flat);
  const core::ExactGeodesics exact(m);
  const auto d = exact.distances(at(m, 1.9, 0.9), {at(m, 0.9, 1.9)});
  CHECK(d[0] == Approx(2 * std::sqrt(0.82)).epsilon(1e-9));
}

TEST_CASE("exact geodesics between two parts of a mesh are infinite", "[core][exact]") {
  const auto m = squares({{0, 0}, {1, 0}, {4, 0}, {5, 0}}, 0, 0, flat);
  const core::ExactGeodesics exact(m);
  const auto d = exact.distances(at(m, 0.5, 0.5), {at(m, 1.5, 0.5), at(m, 5.5, 0.5)});
  CHECK(d[0] == Approx(1.0));
  CHECK(d[1] == std::numeric_limits<double>::infinity());
}

TEST_CASE("exact geodesics refuse a mesh CGAL cannot take, naming the face or vertex",
          "[core][exact][robust]") {
  auto m = squares({{0, 0}}, 0, 0, flat);  // vertices 0 (0,0) 1 (1,0) 2 (1,1) 3 (0,1)
  SECTION("an edge of three faces") {
    m.xyz.insert(m.xyz.end(), {2, 0.5, 0});
    m.faces.push_back({1, 4, 2});  // across edge 1-2 from face 0
    m.faces.push_back({2, 1, 4});  // a third face on edge 1-2
    CHECK_THROWS_WITH(core::ExactGeodesics(m), Catch::StartsWith("face 3 cannot join"));
  }
  SECTION("a folded face: an edge shared in the same direction") {
    m.faces[1] = {0, 3, 2};  // clockwise: its edge 2 -> 0 is face 0's too
    CHECK_THROWS_WITH(core::ExactGeodesics(m), Catch::StartsWith("face 1 cannot join"));
  }
  SECTION("two fans meeting at one vertex") {
    // A second square touching the first only at its corner (1, 1).
    m.xyz.insert(m.xyz.end(), {2, 1, 0, 2, 2, 0, 1, 2, 0});
    m.faces.push_back({2, 4, 5});
    m.faces.push_back({2, 5, 6});
    CHECK_THROWS_WITH(core::ExactGeodesics(m), Catch::StartsWith("vertex 2 joins 4 faces"));
  }
}

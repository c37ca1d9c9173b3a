// Point location on TINs: points on any edge are inside, whatever the coordinates' magnitude.
#include "core/surface_sampling.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "test_support.hpp"

using namespace dpts;

namespace {

// The grid TIN of a 12 x 12 DEM whose valid cells form a staircase (no-data above the diagonal
// c > r + 2: three-corner squares along it, so the outline runs along square diagonals), in UTM
// metres: cells of 9.87654 m from (562193.7312, 5119847.2163), none of it exact in binary.
core::TriMesh staircase_utm() {
  const auto g = test::make_grid(12, 12, [](int c, int r) {
    return c > r + 2 ? std::nan("") : 1200.0 + 3.7 * c - 2.1 * r;
  });
  const auto tin = core::grid_tin(g);
  core::TriMesh m;
  for (auto cell : tin.cells) {
    const int c = static_cast<int>(cell % 12), r = static_cast<int>(cell / 12);
    m.xyz.insert(m.xyz.end(), {562193.7312 + 9.87654 * c, 5119847.2163 - 9.87654 * r, g.z[cell]});
  }
  m.faces = tin.faces;
  core::fix_orientation(m);
  return m;
}

}  // namespace

TEST_CASE("PointLocator finds points on every edge of a UTM-sized TIN inside it",
          "[core][sampling][robust]") {
  const auto m = staircase_utm();
  // Every edge, with the faces using it: the outline's edges (one face) include diagonals.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const auto& f : m.faces) {
    for (int k = 0; k < 3; ++k) {
      const auto a = f[k], b = f[(k + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  const core::PointLocator locate(m);
  std::size_t diagonal_outline = 0, outside = 0;
  for (const auto& [edge, count] : uses) {
    const double* a = &m.xyz[3 * edge.first];
    const double* b = &m.xyz[3 * edge.second];
    const bool diagonal = a[0] != b[0] && a[1] != b[1];
    diagonal_outline += count == 1 && diagonal;
    for (double t : {0.5, 0.3, 1.0 / 3.0, 0.9}) {
      const double x = a[0] + t * (b[0] - a[0]), y = a[1] + t * (b[1] - a[1]);
      const auto hit = locate.locate(x, y);
      if (!hit || hit->snapped) {
        ++outside;
        continue;
      }
      CHECK(hit->point.z == Approx(a[2] + t * (b[2] - a[2])).margin(1e-6));
    }
  }
  CHECK(diagonal_outline == 9);  // one per row of the staircase
  CHECK(outside == 0);
  // Just off the outline (a millimetre) is outside, and snapped with a snap distance.
  const double* a = &m.xyz[0];
  CHECK_FALSE(locate.locate(a[0] - 1e-3, a[1]).has_value());
  const auto snapped = locate.locate(a[0] - 1e-3, a[1], 0.01);
  REQUIRE(snapped.has_value());
  CHECK(snapped->snapped);
}

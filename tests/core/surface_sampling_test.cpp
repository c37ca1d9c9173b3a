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
  const auto g = test::make_grid(
      12, 12, [](int c, int r) { return c > r + 2 ? std::nan("") : 1200.0 + 3.7 * c - 2.1 * r; });
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

TEST_CASE("grid_tin's opposites pair each edge's two half-edges, also once faces are reversed",
          "[core][sampling]") {
  // Random voids (three-corner squares, strands, single cells) on grids of 1 to 8 cells a
  // side, both diagonals, faces as grid_tin gives them and all reversed by fix_orientation
  // (positions x = column, y = row): each half-edge against a search of the faces.
  for (int trial = 0; trial < 80; ++trial) {
    const auto g = test::random_voids_grid(11, trial, [](int c, int r) { return 1.0 * c * r; });
    const int w = g.width, h = g.height;
    for (const auto diagonal : {core::Diagonal::nw_se, core::Diagonal::ne_sw}) {
      for (const bool reverse : {false, true}) {
        std::vector<std::uint32_t> opposites;
        const core::Tin tin = core::grid_tin(g, diagonal, &opposites);
        core::TriMesh m;
        for (const auto cell : tin.cells) {
          const double c = cell % static_cast<std::uint32_t>(w),
                       r = cell / static_cast<std::uint32_t>(w);
          m.xyz.insert(m.xyz.end(), {c, reverse ? r : -r, 0.0});
        }
        m.faces = tin.faces;
        core::fix_orientation(m, &opposites);
        if (reverse && !m.faces.empty()) CHECK(m.faces != tin.faces);
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> half_edge;
        for (std::uint32_t f = 0; f < m.faces.size(); ++f) {
          for (std::uint32_t k = 0; k < 3; ++k)
            half_edge[{m.faces[f][k], m.faces[f][(k + 1) % 3]}] = 3 * f + k;
        }
        std::vector<std::uint32_t> expected(3 * m.faces.size(), core::kNoOpposite);
        for (const auto& [e, hh] : half_edge) {
          const auto it = half_edge.find({e.second, e.first});
          if (it != half_edge.end()) expected[hh] = it->second;
        }
        INFO("trial " << trial << ": " << w << " x " << h << (reverse ? ", reversed" : ""));
        CHECK(opposites == expected);
      }
    }
  }
}

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

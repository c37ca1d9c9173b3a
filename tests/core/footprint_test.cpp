// Tests of the valid footprint: surface vertices, exact point-in-footprint, area.
#include "core/footprint.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "test_support.hpp"

using dpts::core::footprint_area_cells;
using dpts::core::footprint_contains_third;
using dpts::core::FootprintIndex;
using dpts::core::surface_cells;

namespace {
const double kNaN = std::numeric_limits<double>::quiet_NaN();
}

TEST_CASE("a full grid is all surface and its footprint is the cell-centre rectangle",
          "[core][footprint]") {
  const auto g = dpts::test::make_grid(5, 4, [](int c, int r) { return c + r; });
  CHECK(surface_cells(g).size() == 20);
  CHECK(footprint_area_cells(g) == 12.0);  // (5-1) x (4-1)
}

TEST_CASE("a no-data corner of a square leaves the triangle of the other three",
          "[core][footprint]") {
  // 2 x 2 grid with (1,1) missing: the footprint is the triangle (0,0) (1,0) (0,1).
  const auto g =
      dpts::test::make_grid(2, 2, [](int c, int r) { return c == 1 && r == 1 ? kNaN : 0.0; });
  CHECK(surface_cells(g).size() == 3);
  CHECK(footprint_area_cells(g) == 0.5);
  // Centroid of the valid triangle (sums of corners 0+1+0, 0+0+1) is inside; the centroid
  // of the missing one (1+1+0, 0+1+1) is not.
  CHECK(footprint_contains_third(g, 1, 1));
  CHECK_FALSE(footprint_contains_third(g, 2, 2));
  FootprintIndex index(g);
  CHECK(index.contains_third(1, 1));
  CHECK_FALSE(index.contains_third(2, 2));
}

TEST_CASE("isolated cells and one-cell strands are not surface vertices", "[core][footprint]") {
  // Row 0: a single valid cell at column 0 surrounded by voids; row 2: a full 3-cell strand.
  const auto g = dpts::test::make_grid(3, 3, [](int c, int r) {
    if (r == 0) return c == 0 ? 1.0 : kNaN;
    if (r == 1) return kNaN;
    return 2.0;
  });
  CHECK(surface_cells(g).empty());
  CHECK(footprint_area_cells(g) == 0.0);
}

TEST_CASE("surface cells are the corners of squares with three or four valid corners",
          "[core][footprint]") {
  // Random voids at several densities and sizes (one row or column included), against the
  // definition cell by cell: a valid cell is a surface vertex iff one of its four squares has
  // at least three valid corners.
  for (int trial = 0; trial < 60; ++trial) {
    const auto g = dpts::test::random_voids_grid(7, trial, [](int, int) { return 1.0; });
    const int w = g.width, h = g.height;
    auto valid = [&](int c, int r) { return g.is_valid(c, r); };
    auto full = [&](int c, int r) {  // square (c, r) has at least three valid corners
      return valid(c, r) + valid(c + 1, r) + valid(c, r + 1) + valid(c + 1, r + 1) >= 3;
    };
    std::vector<std::uint32_t> expected;
    for (int r = 0; r < h; ++r) {
      for (int c = 0; c < w; ++c) {
        if (valid(c, r) && (full(c, r) || full(c - 1, r) || full(c, r - 1) || full(c - 1, r - 1))) {
          expected.push_back(static_cast<std::uint32_t>(r * w + c));
        }
      }
    }
    INFO("trial " << trial << ": " << w << " x " << h);
    CHECK(surface_cells(g) == expected);
  }
}

TEST_CASE("points on the outline are classified by the infinitesimal push", "[core][footprint]") {
  // 3 x 2 full grid: footprint [0,2] x [0,1]. The push (+eps, +eps^2) moves a point on the
  // right or bottom edge outside and one on the left or top edge inside.
  const auto g = dpts::test::make_grid(3, 2, [](int, int) { return 0.0; });
  CHECK(footprint_contains_third(g, 0, 0));        // corner (0,0): pushed inside
  CHECK_FALSE(footprint_contains_third(g, 6, 0));  // (2,0): pushed right, outside
  CHECK_FALSE(footprint_contains_third(g, 3, 3));  // (1,1): pushed down, outside
  CHECK(footprint_contains_third(g, 3, 1));        // (1, 1/3): inside
  CHECK_FALSE(footprint_contains_third(g, -1, 1));
}

TEST_CASE("GridFrame maps a square north-up grid to integers", "[core][footprint]") {
  const double j[2][2] = {{30.0, 0.0}, {0.0, -30.0}};
  const auto f = dpts::core::GridFrame::from_jacobian(j);
  CHECK(f.metres_per_unit == 30.0);
  CHECK(f.u(7, 5) == 7.0);
  CHECK(f.w(7, 5) == -5.0);
  const double singular[2][2] = {{1.0, 2.0}, {2.0, 4.0}};
  CHECK_THROWS(dpts::core::GridFrame::from_jacobian(singular));
}

TEST_CASE("the footprint index answers as the definition, on full grids and with voids",
          "[core][footprint]") {
  // Every point of thirds over the grid and a cell beyond it: a full grid's index keeps no
  // masks (every square is whole), a voided one looks each square up; both as the definition.
  for (int trial = -2; trial < 30; ++trial) {
    const auto g = trial < 0
                       ? dpts::test::make_grid(5 + trial, 4, [](int c, int r) { return c + r; })
                       : dpts::test::random_voids_grid(7, trial, [](int, int) { return 1.0; });
    const FootprintIndex index(g);
    for (int sr = -3; sr <= 3 * g.height + 3; ++sr) {
      for (int sc = -3; sc <= 3 * g.width + 3; ++sc) {
        INFO("trial " << trial << " thirds (" << sc << ", " << sr << ")");
        CHECK(index.contains_third(sc, sr) == footprint_contains_third(g, sc, sr));
      }
    }
  }
}

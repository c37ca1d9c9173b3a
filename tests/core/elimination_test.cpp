// Vertex elimination on hand-made DEMs: counts, footprint, Delaunay validity, determinism.
#include "core/elimination.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>

#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/predicates.hpp"
#include "core/surface_sampling.hpp"
#include "parallel/simplify.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Hills with a round void inside, a notch cut into the east edge and a missing NW corner:
// concave outline, a hole, and straight outline runs to simplify.
core::HeightGrid hills(int w = 40, int h = 32) {
  return test::make_grid(w, h, [w, h](int c, int r) {
    if (std::hypot(c - 12.0, r - 14.0) < 4.0) return kNaN;            // void
    if (c >= w - 6 && r >= h / 2 - 2 && r <= h / 2 + 2) return kNaN;  // notch
    if (c + r < 3) return kNaN;                                       // cut corner
    return 100.0 + 20.0 * std::sin(c * 0.3) * std::cos(r * 0.25) + 0.5 * c;
  });
}

core::Tin simplify(const core::HeightGrid& g, core::Importance kind, std::size_t keep,
                   core::GridFrame frame = {}) {
  core::EliminationOptions opt;
  opt.importance = kind;
  par::KeepTarget target;
  target.vertices = keep;
  return par::simplify_dem(g, frame, opt, target, nullptr);
}

}  // namespace

TEST_CASE("elimination keeps exactly the requested count and the exact footprint",
          "[core][simplify]") {
  const auto g = hills();
  const std::size_t input = core::surface_cells(g).size();
  const auto kind = GENERATE(core::Importance::vp, core::Importance::pld);
  const double share = GENERATE(0.7, 0.3, 0.1);
  const auto keep = static_cast<std::size_t>(share * input);
  const core::Tin tin = simplify(g, kind, keep);
  CHECK(tin.cells.size() == keep);
  test::check_tin(g, tin);
}

TEST_CASE("the unsimplified TIN is the grid split along NW-SE diagonals", "[core][simplify]") {
  const auto g = test::make_grid(6, 5, [](int c, int r) { return c * r; });
  const core::Tin tin = simplify(g, core::Importance::vp, 30);
  REQUIRE(tin.cells.size() == 30);
  REQUIRE(tin.faces.size() == 2 * 5 * 4);
  // Every face contains a NW-SE diagonal (r,c)-(r+1,c+1): index difference width + 1.
  for (const auto& f : tin.faces) {
    bool diagonal = false;
    for (int i = 0; i < 3; ++i) {
      const auto a = tin.cells[f[i]], b = tin.cells[f[(i + 1) % 3]];
      diagonal |= std::max(a, b) - std::min(a, b) == 7u;
    }
    CHECK(diagonal);
  }
}

TEST_CASE("a plane simplifies to its four corners", "[core][simplify]") {
  const auto g = test::make_grid(12, 9, [](int c, int r) { return 3.0 * c - 2.0 * r + 5.0; });
  const auto kind = GENERATE(core::Importance::vp, core::Importance::pld);
  const core::Tin tin = simplify(g, kind, 4);
  REQUIRE(tin.cells.size() == 4);
  CHECK(tin.cells == std::vector<std::uint32_t>{0, 11, 8 * 12, 8 * 12 + 11});
  CHECK(tin.faces.size() == 2);
  test::check_tin(g, tin);
}

TEST_CASE("links longer than a vertex's home block stay Delaunay", "[core][simplify]") {
  // Flat ground round a void, and a pinned centre amid a pinned circle of cells: VP removes
  // the rest at no cost, and the centre ends with a neighbour for each cell of the circle,
  // past the 15 a vertex's link holds in its own block (elimination.cpp, kHomeLinks): its
  // link spills, and grows there.
  const int w = 48, h = 40;
  const auto g = test::make_grid(w, h, [](int c, int r) {
    if (std::hypot(c - 10.0, r - 30.0) < 4.0) return kNaN;
    return 10.0 + 1e-9 * ((c * 7 + r * 13) % 5);
  });
  core::EliminationOptions opt;
  opt.importance = GENERATE(core::Importance::vp, core::Importance::pld);
  opt.pinned.assign(static_cast<std::size_t>(w) * h, 0);
  const int centre = 18 * w + 30;
  opt.pinned[centre] = 1;
  for (int k = 0; k < 40; ++k) {
    const double t = 2 * M_PI * k / 40;
    opt.pinned[std::lround(18 + 9 * std::sin(t)) * w + std::lround(30 + 9 * std::cos(t))] = 1;
  }
  par::KeepTarget target;
  target.vertices = 4;
  const core::Tin tin = par::simplify_dem(g, {}, opt, target, nullptr);
  test::check_tin(g, tin);
  const auto at = std::lower_bound(tin.cells.begin(), tin.cells.end(), centre);
  REQUIRE((at != tin.cells.end() && *at == static_cast<std::uint32_t>(centre)));
  const auto id = static_cast<std::uint32_t>(at - tin.cells.begin());
  const auto faces = std::count_if(tin.faces.begin(), tin.faces.end(), [id](const auto& f) {
    return f[0] == id || f[1] == id || f[2] == id;
  });
  CHECK(faces > 15);
}

TEST_CASE("corners and bends of the outline are never removed", "[core][simplify]") {
  // Asking for 3 vertices cannot be met: the outline's corners stay, and the result is the
  // smallest TIN with the same footprint.
  const auto g = hills(24, 20);
  const core::Tin tin = simplify(g, core::Importance::vp, 3);
  CHECK(tin.cells.size() > 3);
  test::check_tin(g, tin);
  // The DEM's corners that hold data are kept.
  for (std::uint32_t corner :
       {std::uint32_t(23), std::uint32_t(19 * 24), std::uint32_t(19 * 24 + 23)}) {
    CHECK(std::binary_search(tin.cells.begin(), tin.cells.end(), corner));
  }
}

TEST_CASE("void holes stay open at every level of simplification", "[core][simplify]") {
  // Salt-and-pepper voids like the Kilauea sea: many one-cell holes.
  const auto g = test::make_grid(30, 30, [](int c, int r) {
    if ((c * 7 + r * 13) % 17 == 0 && c > 2 && r > 2) return kNaN;
    return std::sin(c * 0.2) * 50 + r;
  });
  const std::size_t input = core::surface_cells(g).size();
  for (double share : {0.5, 0.2}) {
    const core::Tin tin =
        simplify(g, core::Importance::vp, static_cast<std::size_t>(share * input));
    test::check_tin(g, tin);
  }
}

TEST_CASE("elimination works in a sheared, non-square frame", "[core][simplify]") {
  // Cells 20 m x 31 m with a slight shear, as a geographic DEM projected to UTM.
  const double j[2][2] = {{20.0, 0.4}, {-0.3, -31.0}};
  const auto frame = core::GridFrame::from_jacobian(j);
  const auto g = hills(30, 24);
  const std::size_t input = core::surface_cells(g).size();
  const core::Tin tin = simplify(g, core::Importance::vp, input / 5, frame);
  CHECK(tin.cells.size() == input / 5);
  test::check_tin(g, tin, frame);
}

TEST_CASE("the result does not depend on how initial importance is split", "[core][determinism]") {
  const auto g = hills(30, 24);
  core::EliminationOptions opt;
  opt.vp_volume = GENERATE(core::VolumeMethod::exact, core::VolumeMethod::monte_carlo);
  auto run = [&](std::size_t chunk, bool reverse) {
    core::Eliminator e(g, core::GridFrame{}, opt);
    std::vector<std::pair<std::size_t, std::size_t>> ranges;
    for (std::size_t b = 0; b < e.vertex_count(); b += chunk) {
      ranges.emplace_back(b, std::min(e.vertex_count(), b + chunk));
    }
    if (reverse) std::reverse(ranges.begin(), ranges.end());
    for (auto [b, end] : ranges) e.compute_importance(b, end);
    e.eliminate(e.vertex_count() / 4, nullptr);
    return e.tin();
  };
  const core::Tin a = run(1000000, false), b = run(7, true);
  CHECK(a.cells == b.cells);
  CHECK(a.faces == b.faces);
}

TEST_CASE("lazy exact VP removes the same vertices in the same order", "[core][simplify][vp]") {
  // Hills with voids, and rough ground whose importances crowd together at the top of the
  // queue (where a bound above an importance would change the order).
  const auto g =
      GENERATE(as<int>{}, 0, 1) == 0 ? hills() : test::make_grid(36, 30, [](int c, int r) {
        const double noise = std::fmod(std::sin(c * 12.9898 + r * 78.233) * 43758.5453, 1.0);
        return 2500.0 + 3.0 * noise + 0.2 * c;
      });
  auto run = [&](bool lazy) {
    core::EliminationOptions opt;
    opt.lazy_vp = lazy;
    core::Eliminator e(g, core::GridFrame{}, opt);
    e.compute_importance(0, e.vertex_count());
    e.eliminate(e.vertex_count() / 3, nullptr);
    std::vector<core::Removal> log;  // a second call, as the meta method's tail makes
    e.eliminate(e.vertex_count() / 10, nullptr, &log);
    return std::make_pair(e.tin(), log);
  };
  const auto [eager, eager_log] = run(false);
  const auto [lazy, lazy_log] = run(true);
  CHECK(lazy.cells == eager.cells);
  CHECK(lazy.faces == eager.faces);
  REQUIRE(lazy_log.size() == eager_log.size());
  for (std::size_t k = 0; k < lazy_log.size(); ++k) {
    CHECK(lazy_log[k].cell == eager_log[k].cell);
  }
}

TEST_CASE("a DEM without three neighbouring valid cells is refused", "[core][simplify]") {
  const auto g = test::make_grid(4, 4, [](int c, int r) { return (c + r) % 2 == 0 ? 1.0 : kNaN; });
  CHECK_THROWS_AS(core::Eliminator(g, core::GridFrame{}, core::EliminationOptions{}),
                  std::invalid_argument);
}

TEST_CASE("VP keeps a spike and drops flat ground first", "[core][simplify][vp]") {
  // Flat 15 x 15 with one spike in the middle: at 10 vertices the spike must survive.
  const auto g =
      test::make_grid(15, 15, [](int c, int r) { return c == 7 && r == 7 ? 50.0 : 0.0; });
  const core::Tin tin = simplify(g, core::Importance::vp, 10);
  CHECK(std::binary_search(tin.cells.begin(), tin.cells.end(), std::uint32_t(7 * 15 + 7)));
  test::check_tin(g, tin);
}

TEST_CASE("an outline chord the caller refuses keeps its outline vertices", "[core][simplify]") {
  // A plane would simplify to its 4 corners; refusing every chord longer than 3 cells keeps
  // an outline vertex at least every 3 cells.
  const auto g = test::make_grid(13, 10, [](int c, int r) { return 2.0 * c + r; });
  core::EliminationOptions opt;
  opt.outline_chord_ok = [&](std::uint32_t a, std::uint32_t b) {
    const long dc = std::labs(static_cast<long>(a % 13) - static_cast<long>(b % 13));
    const long dr = std::labs(static_cast<long>(a / 13) - static_cast<long>(b / 13));
    return std::max(dc, dr) <= 3;
  };
  par::KeepTarget target;
  target.vertices = 4;
  const core::Tin tin = par::simplify_dem(g, core::GridFrame{}, opt, target, nullptr);
  // Along each side, kept vertices are at most 3 cells apart (at least 14 on the outline, the
  // optimum; greedy order may keep a few more), and fewer than all 38 outline cells remain.
  std::vector<std::vector<int>> sides(4);  // positions along row 0, row 9, col 0, col 12
  for (std::uint32_t cell : tin.cells) {
    const int c = static_cast<int>(cell % 13), r = static_cast<int>(cell / 13);
    if (r == 0) sides[0].push_back(c);
    if (r == 9) sides[1].push_back(c);
    if (c == 0) sides[2].push_back(r);
    if (c == 12) sides[3].push_back(r);
  }
  std::size_t on_outline = 0;
  for (auto& side : sides) {
    std::sort(side.begin(), side.end());
    for (std::size_t i = 1; i < side.size(); ++i) CHECK(side[i] - side[i - 1] <= 3);
    on_outline += side.size();
  }
  CHECK(on_outline - 4 >= 14);  // corners counted twice
  CHECK(on_outline - 4 < 38);
  CHECK(tin.cells.size() == on_outline - 4);  // the plane's interior is all gone
  test::check_tin(g, tin);
}

TEST_CASE("the unsimplified TIN takes the frame's Delaunay diagonal, as grid_tin says",
          "[core][simplify]") {
  // A reprojected DEM's frame is sheared: Delaunay splits every square along its shorter
  // diagonal, which is NE-SW for one shear and NW-SE for the other (and for a square grid).
  const auto g = hills(20, 16);
  const double shears[3][2][2] = {
      {{20.0, 0.4}, {-0.3, -31.0}}, {{20.0, -0.4}, {0.3, -31.0}}, {{30.0, 0.0}, {0.0, -30.0}}};
  for (const auto& j : shears) {
    const auto frame = core::GridFrame::from_jacobian(j);
    const std::size_t input = core::surface_cells(g).size();
    const core::Tin tin = simplify(g, core::Importance::vp, input, frame);
    const core::Tin grid = core::grid_tin(g, core::delaunay_diagonal(frame));
    // The same triangles, as sets of cells.
    auto as_sets = [](const std::vector<std::uint32_t>& cells, const auto& faces) {
      std::vector<std::array<std::uint32_t, 3>> out;
      for (const auto& f : faces) {
        std::array<std::uint32_t, 3> t{cells[f[0]], cells[f[1]], cells[f[2]]};
        std::sort(t.begin(), t.end());
        out.push_back(t);
      }
      std::sort(out.begin(), out.end());
      return out;
    };
    CHECK(as_sets(tin.cells, tin.faces) == as_sets(grid.cells, grid.faces));
  }
  CHECK(core::delaunay_diagonal(core::GridFrame::from_jacobian(shears[0])) !=
        core::delaunay_diagonal(core::GridFrame::from_jacobian(shears[1])));
}

TEST_CASE("a DEM with every cell valid gets CGAL's TIN straight from its grid",
          "[core][simplify]") {
  // Square cells (cocircular corners: the perturbed test picks the diagonal), rectangles,
  // the shears of reprojected DEMs either way, a rotation, one without the reflection of a
  // north-up DEM, and a shear past the lattice's reduced basis (its Delaunay edges cross
  // squares: the grid is not used, and the TIN must still be CGAL's).
  const double frames[7][2][2] = {{{30.0, 0.0}, {0.0, -30.0}},   {{30.0, 0.0}, {0.0, -10.0}},
                                  {{20.0, 0.4}, {-0.3, -31.0}},  {{20.0, -0.4}, {0.3, -31.0}},
                                  {{26.0, 15.0}, {15.0, -26.0}}, {{30.0, 0.0}, {0.0, 30.0}},
                                  {{10.0, 25.0}, {0.0, -10.0}}};
  const auto g = test::make_grid(23, 17, [](int c, int r) {
    const double noise = std::fmod(std::sin(c * 12.9898 + r * 78.233) * 43758.5453, 1.0);
    return 100.0 + 5.0 * noise + 0.3 * c - 0.2 * r;
  });
  for (const auto& j : frames) {
    const auto frame = core::GridFrame::from_jacobian(j);
    for (const auto kind : {core::Importance::vp, core::Importance::pld}) {
      auto run = [&](bool from_grid, std::size_t keep) {
        core::EliminationOptions opt;
        opt.importance = kind;
        opt.grid_triangulation = from_grid;
        core::Eliminator e(g, frame, opt);
        e.compute_importance(0, e.vertex_count());
        std::vector<core::Removal> log;
        e.eliminate(keep, nullptr, &log);
        return std::make_pair(e.tin(), log);
      };
      for (const std::size_t keep : {std::size_t{23 * 17}, std::size_t{40}}) {
        const auto [grid, grid_log] = run(true, keep);
        const auto [cgal, cgal_log] = run(false, keep);
        INFO("frame " << j[0][0] << " " << j[0][1] << " " << j[1][0] << " " << j[1][1] << ", keep "
                      << keep);
        CHECK(grid.cells == cgal.cells);
        CHECK(grid.faces == cgal.faces);
        REQUIRE(grid_log.size() == cgal_log.size());
        for (std::size_t k = 0; k < grid_log.size(); ++k) {
          CHECK(grid_log[k].cell == cgal_log[k].cell);
        }
        test::check_tin(g, grid, frame);
      }
    }
  }
}

TEST_CASE("the in-circle test on a frame's lattice is CGAL's perturbed one", "[core][simplify]") {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Point = K::Point_2;
  const CGAL::Delaunay_triangulation_2<K> predicates;
  // Square cells (every square cocircular), rectangles, shears, a rotation: points of the
  // frame's lattice within 4 cells of each other, so that many quadruples lie on one circle.
  const double frames[5][2][2] = {{{30.0, 0.0}, {0.0, -30.0}},
                                  {{30.0, 0.0}, {0.0, -10.0}},
                                  {{20.0, 0.4}, {-0.3, -31.0}},
                                  {{26.0, 15.0}, {15.0, -26.0}},
                                  {{1.0, 0.0}, {0.0, -1.3}}};
  std::uint64_t state = 12345;
  auto next = [&](int n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % static_cast<std::uint64_t>(n));
  };
  std::size_t compared = 0, on_circle = 0;
  for (const auto& j : frames) {
    const auto frame = core::GridFrame::from_jacobian(j);
    auto at = [&](int c, int r) { return Point(frame.u(c, r), frame.w(c, r)); };
    for (int trial = 0; trial < 20000; ++trial) {
      // Every other trial within one cell, where most quadruples are a square's corners.
      const int span = trial % 2 ? 3 : 5, half = span / 2;
      const int c0 = 1000 + next(5), r0 = 700 + next(5);
      const Point pts[4] = {at(c0, r0), at(c0 + next(span) - half, r0 + next(span) - half),
                            at(c0 + next(span) - half, r0 + next(span) - half),
                            at(c0 + next(span) - half, r0 + next(span) - half)};
      const Point &a = pts[1], &b = pts[2], &c = pts[3], &p = pts[0];
      if (a == b || b == c || a == c || p == a || p == b || p == c) continue;
      // Either turn: the refill asks counter-clockwise triples, CGAL answers both alike.
      if (CGAL::orientation(a, b, c) == CGAL::COLLINEAR) continue;
      const int lattice =
          core::lattice_in_circle(a.x(), a.y(), b.x(), b.y(), c.x(), c.y(), p.x(), p.y());
      const bool inside =
          predicates.side_of_oriented_circle(a, b, c, p, true) == CGAL::ON_POSITIVE_SIDE;
      REQUIRE(lattice >= 0);
      CHECK((lattice == 1) == inside);
      ++compared;
      if (CGAL::side_of_oriented_circle(a, b, c, p) == CGAL::ON_ORIENTED_BOUNDARY) ++on_circle;
    }
  }
  CHECK(compared > 20000);
  CHECK(on_circle > 800);  // the perturbation is exercised
  // Off the lattice, or too far apart for 128 bits: nothing known.
  CHECK(core::lattice_in_circle(0.1, 0, 1, 0, 0, 1, 0.3, 0.3) == -1);
  CHECK(core::lattice_in_circle(0, 0, 100, 0, 0, 100, 30, 30) == -1);
  CHECK(core::lattice_in_circle(0, 0, 10, 0, 0, 10, 3, 3) == 1);
  CHECK(core::lattice_in_circle(0, 0, 10, 0, 0, 10, 30, 3) == 0);
}

TEST_CASE("the orientation filter answers only with CGAL's exact sign", "[core][simplify]") {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  std::uint64_t state = 99;
  auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1p-53;
  };
  std::size_t answered = 0, doubted = 0;
  for (int trial = 0; trial < 100000; ++trial) {
    // Points near one line (within a few ulps of it, or on it), and anywhere.
    const double ax = 1000 * uniform(), ay = 1000 * uniform();
    const double dx = uniform() - 0.5, dy = uniform() - 0.5;
    const double s = 1000 * uniform(), t = 1000 * uniform();
    const double jitter = trial % 3 == 0 ? 0.0 : trial % 3 == 1 ? 1e-13 * (uniform() - 0.5) : 1;
    const K::Point_2 a(ax, ay), b(ax + s * dx, ay + s * dy), p(ax + t * dx + jitter, ay + t * dy);
    const int sign = core::orientation_filtered(a.x(), a.y(), b.x(), b.y(), p.x(), p.y());
    if (sign == 0) {
      ++doubted;
      continue;
    }
    ++answered;
    CHECK(sign == static_cast<int>(CGAL::orientation(a, b, p)));
  }
  CHECK(answered > 50000);
  CHECK(doubted > 100);  // near-collinear triples are left to the exact test
  CHECK(core::orientation_filtered(0, 0, 1, 0, 2, 0) == 0);
  CHECK(core::orientation_filtered(0, 0, 1, 0, 0, 1) == 1);
  CHECK(core::orientation_filtered(0, 0, 0, 1, 1, 0) == -1);
}

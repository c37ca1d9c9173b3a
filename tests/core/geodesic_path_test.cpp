// Straightened Steiner paths: exact on surfaces with known geodesics, and against CGAL's exact
// geodesics on rough terrain.
#include "core/geodesic_path.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <random>

#include "core/exact_geodesic.hpp"
#include "core/surface_sampling.hpp"
#include "support/exact_geodesic.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

constexpr double kPi = 3.14159265358979323846;

// The grid TIN of z = f(x, y) on a w x h grid of `cell` metre cells from (x0, y0).
core::TriMesh grid_surface(int w, int h, double cell,
                           const std::function<double(double, double)>& f, double x0 = 0,
                           double y0 = 0) {
  const auto g =
      test::make_grid(w, h, [&](int c, int r) { return f(x0 + cell * c, y0 - cell * r); });
  const auto t = core::grid_tin(g);
  core::TriMesh m;
  for (auto c : t.cells) {
    m.xyz.insert(m.xyz.end(), {x0 + cell * (c % w), y0 - cell * (c / w), g.z[c]});
  }
  m.faces = t.faces;
  core::fix_orientation(m);
  return m;
}

// Every point but points[i], in order.
std::vector<core::SurfacePoint> others(const std::vector<core::SurfacePoint>& pts, std::size_t i) {
  std::vector<core::SurfacePoint> out(pts);
  out.erase(out.begin() + static_cast<std::ptrdiff_t>(i));
  return out;
}

// Straightened distances from points[i] to every other point (Steiner search, then straightened).
std::vector<double> straightened(const core::SteinerGraph& g,
                                 const std::vector<core::SurfacePoint>& pts, std::size_t i,
                                 core::PathStraightener& s, std::vector<double>* steiner = nullptr,
                                 bool anchored = false, bool buckets = true) {
  core::GeodesicQuery q(g, buckets);
  q.set_anchored(anchored);
  const auto targets = others(pts, i);
  std::vector<double> d;
  q.distances(pts[i], targets, d);
  if (steiner) *steiner = d;
  for (std::size_t j = 0; j < targets.size(); ++j)
    d[j] = s.shortest(q, pts[i], j, targets[j], d[j]);
  return d;
}

// Random heights on a 16 x 14 grid of 10 m cells: saddles, peaks and pits everywhere, slopes
// up to 250 %.
core::TriMesh rough_terrain() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> height(0.0, 25.0);
  return grid_surface(16, 14, 10.0, [&](double, double) { return height(rng); });
}

// The plane z = 0.3 x - 0.2 y on a 15 x 12 grid of 30 m cells (420 x 330 m) at UTM-sized
// coordinates: x from kPlaneX0, y down from kPlaneY0.
constexpr double kPlaneX0 = 500000.0, kPlaneY0 = 4500000.0;
core::TriMesh tilted_utm_plane() {
  return grid_surface(
      15, 12, 30.0, [](double x, double y) { return 0.3 * x - 0.2 * y; }, kPlaneX0, kPlaneY0);
}

double dist3(const core::SurfacePoint& a, const core::SurfacePoint& b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
                   (a.z - b.z) * (a.z - b.z));
}

}  // namespace

TEST_CASE("straightened paths on a tilted plane are straight lines", "[core][geodesic][exact]") {
  // UTM-sized coordinates, and a graph of edges only (delta longer than every edge): the Steiner
  // path zig-zags along grid edges, the straightened one is the segment.
  const auto m = tilted_utm_plane();
  const core::SteinerGraph g(m, 1000.0);
  core::PathStraightener s(g);
  const auto pts = core::sample_uniform(m, 12, 3);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    std::vector<double> steiner;
    const auto d = straightened(g, pts, i, s, &steiner);
    for (std::size_t j = 0, t = 0; j < pts.size(); ++j) {
      if (j == i) continue;
      CAPTURE(i, j);
      CHECK(steiner[t] > dist3(pts[i], pts[j]) * (1 + 1e-4));  // the graph alone is far off
      CHECK(d[t] == Approx(dist3(pts[i], pts[j])).epsilon(1e-9));
      ++t;
    }
  }
  CHECK(s.stats().failed == 0);
}

TEST_CASE("a path through a vertex where two parts of the mesh meet is straightened in parts",
          "[core][geodesic][exact]") {
  // Two grids of 5 x 5 cells of 10 m on the plane z = 0.3 x - 0.2 y, meeting at one vertex
  // (the first's north-east corner, the second's south-west), as where a DEM's void touches
  // itself corner to corner: a path from one to the other passes there from one fan to the
  // other, which no strip of faces holds. Its geodesic is the two segments through it.
  const auto plane = [](double x, double y) { return 0.3 * x - 0.2 * y; };
  core::TriMesh m = grid_surface(6, 6, 10.0, plane, 0, 50);          // x 0..50, y 0..50
  const core::TriMesh b = grid_surface(6, 6, 10.0, plane, 50, 100);  // x 50..100, y 50..100
  const std::uint32_t shared_a = 5, shared_b = 30;                   // (50, 50) in each
  const auto offset = static_cast<std::uint32_t>(m.vertex_count());
  auto in_m = [&](std::uint32_t v) {
    return v == shared_b ? shared_a : v < shared_b ? offset + v : offset + v - 1;
  };
  for (std::uint32_t v = 0; v < b.vertex_count(); ++v) {
    if (v != shared_b) m.xyz.insert(m.xyz.end(), &b.xyz[3 * v], &b.xyz[3 * v] + 3);
  }
  for (const auto& f : b.faces) m.faces.push_back({in_m(f[0]), in_m(f[1]), in_m(f[2])});
  REQUIRE(m.xyz[3 * shared_a] == 50.0);
  REQUIRE(m.xyz[3 * shared_a + 1] == 50.0);
  core::SteinerGraph g(m, 3.0);
  g.keep_vertex_angles();
  core::PathStraightener s(g);
  const auto pts = core::sample_uniform(m, 16, 5);
  const core::SurfacePoint v{50.0, 50.0, plane(50.0, 50.0), 0};
  auto first = [](const core::SurfacePoint& p) { return p.x + p.y < 100.0; };
  int across = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto d = straightened(g, pts, i, s);
    for (std::size_t j = 0, t = 0; j < pts.size(); ++j) {
      if (j == i) continue;
      CAPTURE(i, j);
      const bool cut = first(pts[i]) != first(pts[j]);
      across += cut;
      const double expected = cut ? dist3(pts[i], v) + dist3(v, pts[j]) : dist3(pts[i], pts[j]);
      CHECK(d[t] == Approx(expected).epsilon(1e-9));
      ++t;
      if (!cut) continue;
      // A route through the vertex, walked by its bends (along) and by its faces (follow),
      // cut there too; follow's route is the two segments.
      const std::vector<std::array<double, 2>> through{{50.0, 50.0}};
      CHECK(s.along(pts[i], through, pts[j]) == Approx(expected).epsilon(1e-9));
      core::PathRoute route;
      CHECK(s.follow(pts[i], through, pts[j], &route) == Approx(expected).epsilon(1e-9));
      CHECK(std::find(route.taut.begin(), route.taut.end(), through[0]) != route.taut.end());
    }
  }
  CHECK(across > 50);
  CHECK(s.stats().failed == 0);
}

TEST_CASE("a path along a given route is pulled taut: the segment on a plane",
          "[core][geodesic][exact]") {
  // Routes that wander (seen from above) still give the straight segment: on a plane every
  // route is of one homotopy. A route that leaves the mesh gives no path.
  const auto m = tilted_utm_plane();
  const core::SteinerGraph g(m, 12.0);
  core::PathStraightener s(g);
  const auto pts = core::sample_uniform(m, 8, 7);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    for (std::size_t j = 0; j < pts.size(); ++j) {
      if (j == i) continue;
      CAPTURE(i, j);
      const double mx = (pts[i].x + pts[j].x) / 2, my = (pts[i].y + pts[j].y) / 2;
      // Halfway, 25 m aside (kept inside the 420 x 330 m grid).
      const double side = mx < kPlaneX0 + 210 ? 25.0 : -25.0;
      const std::vector<std::array<double, 2>> route{{mx + side, my}};
      CHECK(s.along(pts[i], route, pts[j]) == Approx(dist3(pts[i], pts[j])).epsilon(1e-9));
      CHECK(s.along(pts[i], {}, pts[j]) == Approx(dist3(pts[i], pts[j])).epsilon(1e-9));
      CHECK(s.follow(pts[i], route, pts[j]) == Approx(dist3(pts[i], pts[j])).epsilon(1e-9));
      CHECK(s.follow(pts[i], {}, pts[j]) == Approx(dist3(pts[i], pts[j])).epsilon(1e-9));
      const std::vector<std::array<double, 2>> off{{kPlaneX0 - 100, my}};
      CHECK(s.along(pts[i], off, pts[j]) < 0);
      CHECK(s.follow(pts[i], off, pts[j]) < 0);
    }
  }
}

TEST_CASE("a route through a corner of the outline turns there into the faces ahead",
          "[core][geodesic][exact]") {
  // A flat L (a 100 m square less its north-east quarter): from the south-east arm to the
  // north-west one the shortest path bends at the inner corner (50, -50), on the outline. The
  // walk along the route reaches that corner in a face of the south-east arm, from which the
  // segment on leaves through other faces around the corner, not across the outline.
  auto m = grid_surface(11, 11, 10.0, [](double, double) { return 0.0; });
  std::vector<std::array<std::uint32_t, 3>> kept;
  for (const auto& f : m.faces) {
    double cx = 0, cy = 0;
    for (auto v : f) {
      cx += m.xyz[3 * v] / 3;
      cy += m.xyz[3 * v + 1] / 3;
    }
    if (!(cx > 50 && cy > -50)) kept.push_back(f);
  }
  m.faces = kept;
  const core::SteinerGraph g(m, 4.0);
  core::PathStraightener s(g);
  const core::PointLocator locate(m);
  const auto a = locate.locate(80, -70), b = locate.locate(30, -20);
  REQUIRE(a);
  REQUIRE(b);
  const double expected = 2 * std::hypot(30.0, 20.0);
  const std::vector<std::array<double, 2>> corner{{50, -50}};
  CHECK(s.along(a->point, corner, b->point) == Approx(expected).epsilon(1e-9));
  CHECK(s.along(b->point, corner, a->point) == Approx(expected).epsilon(1e-9));
  CHECK(s.follow(a->point, corner, b->point) == Approx(expected).epsilon(1e-9));
  CHECK(s.follow(b->point, corner, a->point) == Approx(expected).epsilon(1e-9));
  // A route cutting across the missing quarter leaves the mesh: no path.
  const std::vector<std::array<double, 2>> across{{60, -40}};
  CHECK(s.along(a->point, across, b->point) < 0);
  CHECK(s.follow(a->point, across, b->point) < 0);
}

TEST_CASE("a straightened path's taut route, followed, gives the path back, also on cliffs",
          "[core][geodesic][exact]") {
  // The synthetic volcano of bench/synthetic_dems.py: a cone with a crater and a 150 m deep
  // canyon four 30 m cells wide, walls from one cell to the next. Every pair's straightened
  // path, told by its taut points (PathRoute::taut: thinned to 5 % of delta) and followed on
  // the same mesh, comes out as long as it was: the same strip of faces. (Told by its bends
  // alone, straight from above between them, 16 of these 435 paths came out up to 0.2 %
  // longer: on the walls a path seen from above is far from straight.)
  const auto m = grid_surface(120, 120, 30.0, [](double x, double y) {
    const double c = x / 30 - 60, r = -y / 30 - 60, d = std::hypot(c, r);
    const double h = 400 * std::exp(-(d / 35) * (d / 35)) - 250 * std::exp(-(d / 10) * (d / 10));
    return std::abs(c - 0.3 * r - 20) < 2 && r > 0 ? h - 150 : h;
  });
  const core::SteinerGraph g(m, 0.5 * core::mean_edge_length(m));
  const auto pts = core::sample_uniform(m, 30, 5);
  core::GeodesicQuery q(g);
  q.set_anchored(true);
  core::PathStraightener s(g);
  std::size_t exact = 0, pairs = 0;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const std::vector<core::SurfacePoint> targets(pts.begin() + static_cast<std::ptrdiff_t>(i) + 1,
                                                  pts.end());
    std::vector<double> d;
    q.distances(pts[i], targets, d);
    for (std::size_t j = 0; j < targets.size(); ++j) {
      CAPTURE(i, j);
      core::PathRoute route;
      const double len = s.shortest(q, pts[i], j, targets[j], d[j], &route);
      const double followed = s.follow(pts[i], route.taut, targets[j]);
      // note: both are real paths; a followed one a hair shorter found a hair more.
      CHECK(followed >= len * (1 - 1e-6));
      CHECK(followed <= len * (1 + 1e-4));
      exact += std::abs(followed - len) <= len * 1e-9;
      ++pairs;
    }
  }
  // note: thinned, a few taut routes pass a vertex the path grazed on its other side.
  CHECK(exact >= pairs * 9 / 10);
}

TEST_CASE("straightened paths over a ridge and a valley are straight when unfolded",
          "[core][geodesic][exact]") {
  // z = slope * |x - 150| (a ridge for slope < 0, a valley for slope > 0): unfolded, each side
  // is a plane of slant factor k, so the geodesic is sqrt((k (|x1 - 150| + |x2 - 150|))^2 + dy^2)
  // between points on opposite sides, and the segment on one side.
  for (double slope : {-0.8, 0.6}) {
    CAPTURE(slope);
    const auto m =
        grid_surface(11, 9, 30.0, [&](double x, double) { return slope * std::fabs(x - 150); });
    const double k = std::sqrt(1 + slope * slope);
    const core::SteinerGraph g(m, 45.0);
    core::PathStraightener s(g);
    const auto pts = core::sample_uniform(m, 14, 5);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const auto d = straightened(g, pts, i, s);
      for (std::size_t j = 0, t = 0; j < pts.size(); ++j) {
        if (j == i) continue;
        const double a = pts[i].x - 150, b = pts[j].x - 150, dy = pts[i].y - pts[j].y;
        const double exact =
            a * b < 0 ? std::hypot(k * (std::fabs(a) + std::fabs(b)), dy) : dist3(pts[i], pts[j]);
        CAPTURE(i, j, pts[i].x, pts[j].x);
        CHECK(d[t++] == Approx(exact).epsilon(1e-9));
      }
    }
    CHECK(s.stats().failed == 0);
  }
}

TEST_CASE("straightened paths on a pyramid are straight in its unfolded fan",
          "[core][geodesic][exact]") {
  // A 16-sided pyramid (a polyhedral cone): its lateral faces unfold around the apex into a
  // fan of total angle B < 2 pi; between points at slant distances r1, r2 and unfolded angle
  // D apart, the geodesic is sqrt(r1^2 + r2^2 - 2 r1 r2 cos(min(D, B - D))).
  const int n = 16;
  const double radius = 100, height = 70;
  const core::TriMesh m = test::pyramid_mesh(n, radius, height);
  // Each face's angle at the apex; a point's unfolded angle is the angles of the faces before
  // its own plus its angle from the face's first edge.
  const double slant = std::hypot(radius, height);
  const double chord = 2 * radius * std::sin(kPi / n);
  const double beta = 2 * std::asin(chord / (2 * slant));
  auto polar = [&](const core::SurfacePoint& p) {
    const double r = std::sqrt(p.x * p.x + p.y * p.y + (p.z - height) * (p.z - height));
    const auto& f = m.faces[p.face];
    const double ex = m.xyz[3 * f[1]], ey = m.xyz[3 * f[1] + 1], ez = m.xyz[3 * f[1] + 2] - height;
    const double cosg = (p.x * ex + p.y * ey + (p.z - height) * ez) / (r * slant);
    return std::pair<double, double>{r, p.face * beta + std::acos(std::clamp(cosg, -1.0, 1.0))};
  };
  const core::SteinerGraph g(m, 20.0);
  core::PathStraightener s(g);
  const auto pts = core::sample_uniform(m, 16, 9);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto d = straightened(g, pts, i, s);
    for (std::size_t j = 0, t = 0; j < pts.size(); ++j) {
      if (j == i) continue;
      const auto [r1, a1] = polar(pts[i]);
      const auto [r2, a2] = polar(pts[j]);
      const double delta = std::fabs(a1 - a2), angle = std::min(delta, n * beta - delta);
      const double exact = std::sqrt(r1 * r1 + r2 * r2 - 2 * r1 * r2 * std::cos(angle));
      CAPTURE(i, j);
      CHECK(d[t++] == Approx(exact).epsilon(1e-9));
    }
  }
  CHECK(s.stats().failed == 0);
}

TEST_CASE("straightened paths on rough terrain are exact but for a few near ties",
          "[core][geodesic][exact]") {
  // Random heights (saddles, peaks and pits everywhere, slopes up to 250 %) at a coarse delta,
  // against CGAL's exact geodesics: Steiner paths several percent long become exact, but for
  // pairs with two routes of nearly equal length around some peak, where the Steiner graph may
  // rank the longer one first: never below the exact distance, never above the Steiner one.
  const auto m = rough_terrain();
  const core::SteinerGraph g(m, 12.0);
  const core::ExactGeodesics exact_geodesics(m);
  core::PathStraightener s(g);
  const auto pts = core::sample_uniform(m, 12, 4);
  double sum = 0, sum_steiner = 0;
  std::size_t pairs = 0, exact_pairs = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    std::vector<double> steiner;
    const auto d = straightened(g, pts, i, s, &steiner);
    const auto targets = others(pts, i);
    const auto exact = exact_geodesics.distances(pts[i], targets);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      CAPTURE(i, t);
      CHECK(d[t] >= exact[t] * (1 - 1e-9));
      CHECK(d[t] <= steiner[t]);
      sum += d[t] / exact[t] - 1;
      sum_steiner += steiner[t] / exact[t] - 1;
      exact_pairs += d[t] < exact[t] * (1 + 1e-9);
      ++pairs;
    }
  }
  CAPTURE(sum / pairs, sum_steiner / pairs, exact_pairs, pairs);
  CHECK(sum_steiner / pairs > 0.02);
  CHECK(sum / pairs < 0.1 * sum_steiner / pairs);
  CHECK(exact_pairs > pairs / 2);
  CHECK(s.stats().failed == 0);
}

TEST_CASE("a straightener reused over many paths gives each the length a fresh one gives",
          "[core][geodesic]") {
  // A straightener keeps what its passes did (each pass redoes only what its reroutes changed)
  // and each face's unfolding, by face, for later passes and later paths: a length must not
  // depend on the paths pulled taut before it. Rough heights, so paths reroute over many
  // passes, on more faces (15,642) than the unfolding cache has slots, so entries are evicted.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> height(0.0, 12.0);
  const auto m = grid_surface(100, 80, 10.0, [&](double, double) { return height(rng); });
  const core::SteinerGraph g(m, 12.0);
  const auto pts = core::sample_uniform(m, 10, 3);
  core::PathStraightener reused(g);
  std::size_t paths = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    core::GeodesicQuery q(g);
    q.set_anchored(true);
    const auto targets = others(pts, i);
    std::vector<double> d;
    q.distances(pts[i], targets, d);
    for (std::size_t j = 0; j < targets.size(); ++j) {
      core::PathStraightener fresh(g);
      CAPTURE(i, j);
      CHECK(reused.shortest(q, pts[i], j, targets[j], d[j]) ==
            fresh.shortest(q, pts[i], j, targets[j], d[j]));
      paths += fresh.stats().paths;
    }
  }
  CHECK(reused.stats().paths == paths);
  CHECK(reused.stats().passes > 2 * reused.stats().paths);
  CHECK(reused.stats().failed == 0);
}

TEST_CASE("anchored searches find the shortest route where the Steiner graph ranks near ties wrong",
          "[core][geodesic][exact]") {
  // The rough terrain above, at a coarse delta: the Steiner graph's lengths, each several
  // percent long by an amount that differs from route to route, rank the longer of two nearly
  // equal routes first for some pairs; an anchored search's lengths are those of paths straight
  // across faces, real paths (never below exact, but for its float anchors) barely longer than
  // the geodesic (here, with under one Steiner point an edge, a quarter of the graph's excess),
  // so it ranks them right far more often (here 6x less error once straightened).
  const auto m = rough_terrain();
  const core::SteinerGraph g(m, 12.0);
  const core::ExactGeodesics exact_geodesics(m);
  core::PathStraightener plain(g), anchored(g);
  const auto pts = core::sample_uniform(m, 12, 4);
  double sum_plain = 0, sum_anchored = 0, sum_search = 0, sum_steiner = 0;
  std::size_t pairs = 0, exact_pairs = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    std::vector<double> steiner, search;
    const auto dp = straightened(g, pts, i, plain, &steiner);
    const auto da = straightened(g, pts, i, anchored, &search, true);
    const auto targets = others(pts, i);
    const auto exact = exact_geodesics.distances(pts[i], targets);
    for (std::size_t t = 0; t < targets.size(); ++t) {
      CAPTURE(i, t, search[t], steiner[t], exact[t]);
      CHECK(search[t] >= exact[t] * (1 - 1e-6));
      CHECK(da[t] >= exact[t] * (1 - 1e-9));
      sum_plain += dp[t] / exact[t] - 1;
      sum_anchored += da[t] / exact[t] - 1;
      sum_search += search[t] / exact[t] - 1;
      sum_steiner += steiner[t] / exact[t] - 1;
      exact_pairs += da[t] < exact[t] * (1 + 1e-9);
      ++pairs;
    }
  }
  CAPTURE(sum_plain / pairs, sum_anchored / pairs, sum_search / pairs, sum_steiner / pairs,
          exact_pairs, pairs);
  CHECK(sum_search / pairs < 0.5 * sum_steiner / pairs);
  CHECK(sum_anchored / pairs < 0.25 * sum_plain / pairs);
  CHECK(exact_pairs > pairs * 3 / 4);
  CHECK(anchored.stats().failed == 0);

  // The heap (used where a degenerate face rules the buckets out) gives the same lengths (here
  // to 1e-9; an anchored label may lower a node below the one settling, so the order within a
  // bucket could matter in principle).
  core::PathStraightener on_heap(g);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    std::vector<double> search, heap_search;
    const auto da = straightened(g, pts, i, anchored, &search, true);
    const auto dh = straightened(g, pts, i, on_heap, &heap_search, true, false);
    for (std::size_t t = 0; t < da.size(); ++t) {
      CAPTURE(i, t);
      CHECK(heap_search[t] == Approx(search[t]).epsilon(1e-6));
      CHECK(dh[t] == Approx(da[t]).epsilon(1e-6));
    }
  }
}

TEST_CASE("print straightened accuracy on real crops", "[.accuracy]") {
  for (const auto& [file, c0, r0] :
       {std::tuple<const char*, int, int>{"st_helens_crater.tif", 39, 39},
        {"san_gabriel_bigtujunga_utm11.tif", 600, 300}}) {
    const auto m = test::dem_crop(test::shared_data(file), c0, r0, 50);
    const double edge = core::mean_edge_length(m);
    const auto pts = core::sample_uniform(m, 24, 7);
    std::vector<std::vector<double>> exact(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const auto targets = others(pts, i);
      exact[i] = core::ExactGeodesics(m).distances(pts[i], targets);
    }
    for (double f : {1.0, 0.25, 0.1}) {
      const core::SteinerGraph g(m, f * edge);
      core::PathStraightener s(g);
      double sum = 0, mx = 0, ssum = 0, smx = 0;
      std::size_t n = 0, bad = 0, h[5] = {0, 0, 0, 0, 0};
      for (std::size_t i = 0; i < pts.size(); ++i) {
        std::vector<double> st;
        const auto d = straightened(g, pts, i, s, &st);
        for (std::size_t t = 0; t < d.size(); ++t) {
          const double e = d[t] / exact[i][t] - 1, se = st[t] / exact[i][t] - 1;
          sum += e, mx = std::max(mx, e), ssum += se, smx = std::max(smx, se), ++n;
          if (e > 1e-6) ++bad;
          for (int b = 0; b < 5; ++b) h[b] += e > std::pow(10.0, -8 + b);
        }
      }
      std::printf(
          "%s f=%.2f steiner mean %.5f%% max %.4f%% | straight mean %.6f%% max %.5f%% min %.2e bad "
          "%zu/%zu passes %.2f reroutes %.2f failed %zu\n",
          file, f, 100 * ssum / n, 100 * smx, 100 * sum / n, 100 * mx, 0.0, bad, n,
          double(s.stats().passes) / s.stats().paths, double(s.stats().reroutes) / s.stats().paths,
          s.stats().failed);
      std::printf("   >1e-8 %zu >1e-7 %zu >1e-6 %zu >1e-5 %zu >1e-4 %zu\n", h[0], h[1], h[2], h[3],
                  h[4]);
    }
  }
}

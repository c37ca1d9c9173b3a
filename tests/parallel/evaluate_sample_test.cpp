// The evaluator never silently wrong: exact reference geodesics, given sample points, pairs a
// mesh disconnects, pairs the DEM does not connect.
#include <tbb/global_control.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "core/errors.hpp"
#include "core/exact_geodesic.hpp"
#include "core/surface_sampling.hpp"
#include "parallel/evaluate.hpp"
#include "parallel/exact_pairwise.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

// The grid TIN (10 m cells) of a w x h grid of bumps; cells where `hole` holds are no-data.
core::TriMesh bumps(int w, int h, bool (*hole)(int, int) = nullptr) {
  const auto g = test::make_grid(w, h, [&](int c, int r) {
    if (hole && hole(c, r)) return std::numeric_limits<double>::quiet_NaN();
    return 20.0 * std::sin(c * 0.7) * std::cos(r * 0.5) + 3.0 * c;
  });
  const auto tin = core::grid_tin(g);
  core::TriMesh m;
  for (auto cell : tin.cells) {
    m.xyz.insert(m.xyz.end(),
                 {10.0 * (cell % w), -10.0 * (cell / w), g.z[cell]});
  }
  m.faces = tin.faces;
  core::fix_orientation(m);
  return m;
}

// mesh cut along x = x_cut: faces east of it get their own copies of the vertices on it (two
// parts that touch but share no edge).
core::TriMesh cut_at(const core::TriMesh& m, double x_cut) {
  core::TriMesh out = m;
  std::vector<std::uint32_t> copy(m.vertex_count(), 0xFFFFFFFFu);
  for (auto& f : out.faces) {
    const double cx = (m.xyz[3 * f[0]] + m.xyz[3 * f[1]] + m.xyz[3 * f[2]]) / 3;
    if (cx < x_cut) continue;
    for (auto& v : f) {
      if (m.xyz[3 * v] != x_cut) continue;
      if (copy[v] == 0xFFFFFFFFu) {
        copy[v] = static_cast<std::uint32_t>(out.vertex_count());
        out.xyz.insert(out.xyz.end(), {m.xyz[3 * v], m.xyz[3 * v + 1], m.xyz[3 * v + 2]});
      }
      v = copy[v];
    }
  }
  return out;
}

par::EvalOptions options(int points, int sets, bool exact) {
  par::EvalOptions o;
  o.points = points;
  o.sets = sets;
  o.exact = exact;
  return o;
}

}  // namespace

TEST_CASE("exact pairwise distances are each source's exact distances, for 1 and 2 threads",
          "[parallel][evaluate][exact][determinism]") {
  const auto m = bumps(12, 12);
  const core::ExactGeodesics exact(m);
  const auto points = core::sample_uniform(m, 9, 3);
  std::vector<double> d[2];
  for (int threads = 1; threads <= 2; ++threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism,
                          static_cast<std::size_t>(threads));
    std::size_t reports = 0;
    d[threads - 1] = par::exact_pairwise_distances(exact, points, [&](std::size_t done) {
      CHECK(done == ++reports);
      return true;
    });
    CHECK(reports == 8);
  }
  // Answering false stops the sources not yet started.
  std::size_t reports = 0;
  CHECK_THROWS_AS(par::exact_pairwise_distances(exact, points,
                                                [&](std::size_t) { return ++reports < 3; }),
                  Cancelled);
  CHECK(reports < 8);
  CHECK(d[0] == d[1]);
  const std::size_t k = points.size();
  const auto from_2 = exact.distances(points[2], {points[5], points[8]});
  CHECK(d[0][2 * k + 5] == from_2[0]);
  CHECK(d[0][2 * k + 8] == from_2[1]);
  CHECK(d[0][5 * k + 2] == 0.0);  // only i < j is filled
}

TEST_CASE("the exact reference gives error 0 for the DEM's own TIN and keeps every pair",
          "[parallel][evaluate][exact]") {
  const auto t = bumps(12, 12);
  auto opt = options(8, 2, true);
  opt.keep_pairs = true;
  const auto same = par::evaluate_distances(t, t, opt);
  CHECK(same.exact);
  CHECK(same.distance_error == 0.0);
  CHECK(same.pairs_measured == 2 * 28);
  REQUIRE(same.pairs.size() == 2 * 28);
  CHECK(same.pairs[0].set == 0);
  CHECK(same.pairs[0].i == 0);
  CHECK(same.pairs[0].j == 1);
  CHECK(same.pairs.back().set == 1);
  CHECK(same.pairs.back().i == 6);
  CHECK(same.pairs.back().j == 7);
  // A coarser mesh of the same DEM (every other row and column) differs.
  core::TriMesh coarse;
  const auto g = test::make_grid(6, 6, [](int c, int r) {
    return 20.0 * std::sin(2 * c * 0.7) * std::cos(2 * r * 0.5) + 6.0 * c;
  });
  const auto tin = core::grid_tin(g);
  for (auto cell : tin.cells) {
    const double x = 20.0 * (cell % 6) * 11.0 / 10.0, y = -20.0 * (cell / 6) * 11.0 / 10.0;
    coarse.xyz.insert(coarse.xyz.end(), {x, y, g.z[cell]});
  }
  coarse.faces = tin.faces;
  core::fix_orientation(coarse);
  const auto r = par::evaluate_distances(t, coarse, options(8, 2, true));
  CHECK(r.distance_error > 0);
  CHECK(r.set_errors.size() == 2);
}

TEST_CASE("given sample points are measured as given, set by set",
          "[parallel][evaluate][sample]") {
  const auto t = bumps(12, 12);
  auto opt = options(100, 3, true);
  opt.keep_pairs = true;
  // Two sets of three points: inside faces, on an edge, on a vertex.
  opt.sample_xy = {{{15.0, -15.0}, {55.0, -50.0}, {100.0, -100.0}},
                   {{0.0, 0.0}, {33.3, -71.7}, {110.0, -40.0}}};
  const auto r = par::evaluate_distances(t, t, opt);
  CHECK(r.set_errors.size() == 2);
  REQUIRE(r.pairs.size() == 6);
  const core::PointLocator locate(t);
  const core::ExactGeodesics exact(t);
  const auto p = locate.locate(33.3, -71.7)->point, q = locate.locate(110.0, -40.0)->point;
  CHECK(r.pairs[5].set == 1);
  CHECK(r.pairs[5].i == 1);
  CHECK(r.pairs[5].j == 2);
  CHECK(r.pairs[5].on_t == exact.distances(p, {q})[0]);
  // A point outside T: an error with the count, naming the set as the file numbers it.
  opt.sample_xy[1][2] = {500.0, -40.0};
  opt.sample_xy[1][0] = {-0.001, 0.0};
  CHECK_THROWS_WITH(par::evaluate_distances(t, t, opt),
                    "2 of 3 points of sample set 1 lie outside the DEM's footprint");
}

TEST_CASE("pairs the DEM connects but the mesh does not fail the evaluation with their count",
          "[parallel][evaluate][robust]") {
  const auto t = bumps(12, 12);
  const auto slit = cut_at(t, 50.0);  // two parts, west and east of x = 50 m
  for (bool exact : {false, true}) {
    CAPTURE(exact);
    auto opt = options(4, 1, exact);
    opt.sample_xy = {{{15.0, -15.0}, {25.0, -75.0}, {85.0, -35.0}, {95.0, -95.0}}};
    CHECK_THROWS_AS(par::evaluate_distances(t, slit, opt), InputError);
    CHECK_THROWS_WITH(par::evaluate_distances(t, slit, opt),
                      "the mesh does not connect 4 of the 6 pairs of sample set 0 that T "
                      "connects (is it in several parts, or slit?)");
  }
}

TEST_CASE("pairs the DEM does not connect are left out and counted, never silently",
          "[parallel][evaluate][robust]") {
  // Two islands of valid cells, west and east of a no-data column.
  const auto t = bumps(12, 10, [](int c, int) { return c == 6; });
  for (bool exact : {false, true}) {
    CAPTURE(exact);
    const auto r = par::evaluate_distances(t, t, options(8, 2, exact));
    CHECK(r.pairs_unconnected > 0);
    CHECK(r.pairs_measured + r.pairs_unconnected == 2 * 28);
    CHECK(r.distance_error == 0.0);
  }
  // A set with nothing to measure: its two points on different islands, or at one position.
  auto opt = options(2, 1, true);
  opt.sample_xy = {{{15.0, -15.0}, {85.0, -35.0}}};
  CHECK_THROWS_WITH(par::evaluate_distances(t, t, opt),
                    "sample set 0: none of its 1 pairs can be measured (1 not connected on T, 0 "
                    "at distance 0 on T)");
  opt.sample_xy = {{{15.0, -15.0}, {15.0, -15.0}, {25.0, -25.0}}};
  const auto r = par::evaluate_distances(t, t, opt);
  CHECK(r.pairs_coincident == 1);
  CHECK(r.pairs_measured == 2);
}

// dpts's quadric edge collapse (qem): exact count, no folds, the footprint kept exactly on
// fewer outline vertices, the chord test asked, locked vertices untouched, quadrics carried.
#include "core/qem.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <set>

#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/surface_sampling.hpp"
#include "test_support.hpp"

using namespace dpts;

TEST_CASE("qem keeps the count and the footprint on fewer outline vertices, no folds",
          "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  const auto in_border = test::border_points(in);
  const double in_area = core::mesh_area(core::xy_of(in.xyz), in.faces);
  for (std::size_t keep : {in.vertex_count() / 2, in.vertex_count() / 10}) {
    INFO("keep " << keep);
    const core::QemResult r = core::qem_simplify(in, keep);
    const core::TriMesh& out = r.mesh;
    CHECK(out.vertex_count() == keep);
    CHECK(r.input_vertices == in.vertex_count());
    CHECK(r.collapses == in.vertex_count() - keep);
    REQUIRE(r.source.size() == keep);
    REQUIRE(r.quadrics.size() == keep);
    const core::MeshCheck mc = core::check_mesh(core::xy_of(out.xyz), out.faces);
    CHECK(mc.clockwise_or_flat == 0);
    CHECK(mc.bad_edges == 0);
    CHECK(mc.area == Approx(in_area).epsilon(1e-12));
    const auto out_border = test::border_points(out);
    for (const auto& p : out_border) CHECK(in_border.count(p) == 1);
    CHECK(out_border.size() <
          (keep < in.vertex_count() / 5 ? in_border.size() / 2 : in_border.size()));
    for (std::pair<double, double> corner : {std::pair{39.0, 0.0}, {0.0, -31.0}, {39.0, -31.0}}) {
      CHECK(out_border.count(corner) == 1);
    }
    // A vertex on the border never moved: it is where its source vertex was.
    for (std::size_t v = 0; v < keep; ++v) {
      if (out_border.count({out.xyz[3 * v], out.xyz[3 * v + 1]}) == 0) continue;
      CHECK(out.xyz[3 * v] == in.xyz[3 * r.source[v]]);
      CHECK(out.xyz[3 * v + 1] == in.xyz[3 * r.source[v] + 1]);
      CHECK(out.xyz[3 * v + 2] == in.xyz[3 * r.source[v] + 2]);
    }
  }
}

TEST_CASE("qem asks the chord test and keeps the outline when it refuses", "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  core::QemOptions options;
  std::size_t asked = 0;
  options.outline_chord_ok = [&](std::uint32_t a, std::uint32_t b) {
    ++asked;
    CHECK(a < in.vertex_count());
    CHECK(b < in.vertex_count());
    return false;
  };
  const core::QemResult r = core::qem_simplify(in, in.vertex_count() / 5, options);
  CHECK(asked > 0);
  CHECK(test::border_points(r.mesh) == test::border_points(in));
}

TEST_CASE("qem never moves or removes a locked vertex", "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  core::QemOptions options;
  options.locked.assign(in.vertex_count(), 0);
  std::set<std::uint32_t> locked;
  // A column of vertices through the middle (a seam), and every 7th vertex.
  for (std::uint32_t v = 0; v < in.vertex_count(); ++v) {
    if (in.xyz[3 * v] == 20.0 || v % 7 == 0) options.locked[v] = 1, locked.insert(v);
  }
  const core::QemResult r = core::qem_simplify(in, in.vertex_count() / 4, options);
  std::size_t found = 0;
  for (std::size_t v = 0; v < r.source.size(); ++v) {
    if (!locked.count(r.source[v])) continue;
    ++found;
    for (int k = 0; k < 3; ++k) CHECK(r.mesh.xyz[3 * v + k] == in.xyz[3 * r.source[v] + k]);
  }
  CHECK(found == locked.size());
  const core::MeshCheck mc = core::check_mesh(core::xy_of(r.mesh.xyz), r.mesh.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
}

TEST_CASE("qem never collapses an edge at a frozen vertex", "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  core::QemOptions options;
  options.frozen.assign(in.vertex_count(), 0);
  std::set<std::uint32_t> frozen;
  for (std::uint32_t v = 0; v < in.vertex_count(); ++v) {
    if (in.xyz[3 * v] == 20.0) options.frozen[v] = 1, frozen.insert(v);
  }
  const core::QemResult r = core::qem_simplify(in, in.vertex_count() / 4, options);
  // Each frozen vertex is there, unmoved, with its own quadric alone (none collapsed onto it).
  const core::QemResult none = core::qem_simplify(in, in.vertex_count());
  std::size_t found = 0;
  for (std::size_t v = 0; v < r.source.size(); ++v) {
    if (!frozen.count(r.source[v])) continue;
    ++found;
    for (int k = 0; k < 3; ++k) CHECK(r.mesh.xyz[3 * v + k] == in.xyz[3 * r.source[v] + k]);
    const double above[3] = {in.xyz[3 * r.source[v]], in.xyz[3 * r.source[v] + 1],
                             in.xyz[3 * r.source[v] + 2] + 1};
    CHECK(r.quadrics[v](above) == Approx(none.quadrics[r.source[v]](above)));
  }
  CHECK(found == frozen.size());
  CHECK(r.mesh.vertex_count() == in.vertex_count() / 4);
}

TEST_CASE("qem in two steps: below a cost bound, then on to the count as in one", "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  const std::size_t keep = in.vertex_count() / 10;
  const core::QemResult plain = core::qem_simplify(in, keep);
  core::QemCollapse c(in, {});
  CHECK(c.vertices() == in.vertex_count());
  std::vector<float> costs;
  c.queued_costs(costs);
  CHECK(costs.size() > in.vertex_count());  // about 3 edges a vertex
  // The median queued cost bounds a first step: it stops short of the count.
  std::nth_element(costs.begin(), costs.begin() + costs.size() / 2, costs.end());
  const double bound = costs[costs.size() / 2];
  const std::size_t first = c.collapse(keep, bound);
  CHECK(first > 0);
  CHECK(c.vertices() > keep);
  // The plain run's collapses cost as much as the bound by then, not before: the same first
  // collapses (each under the bound) were made.
  const std::size_t rest = c.collapse(keep, std::numeric_limits<double>::infinity());
  CHECK(first + rest == in.vertex_count() - keep);
  const core::QemResult two = c.result();
  CHECK(two.collapses == plain.collapses);
  CHECK(two.input_vertices == in.vertex_count());
  CHECK(two.mesh.faces == plain.mesh.faces);
  CHECK(two.mesh.xyz == plain.mesh.xyz);
  CHECK(two.source == plain.source);
}

TEST_CASE("qem refuses a triangle the bound refuses, and goes on with the others", "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  core::QemOptions options;
  std::size_t asked = 0;
  // Refuse every triangle wider than 6 units: the mesh cannot go below some count.
  options.triangle_ok = [&](const double* a, const double* b, const double* c) {
    ++asked;
    for (const double* p : {a, b, c}) {
      for (const double* q : {a, b, c}) {
        if (std::hypot(p[0] - q[0], p[1] - q[1]) > 6.0) return false;
      }
    }
    return true;
  };
  const core::QemResult r = core::qem_simplify(in, 3, options);
  CHECK(asked > 0);
  CHECK(r.refused > 0);
  CHECK(r.mesh.vertex_count() > 3);
  for (const auto& f : r.mesh.faces) {
    for (int i = 0; i < 3; ++i) {
      const double* p = &r.mesh.xyz[3 * f[i]];
      const double* q = &r.mesh.xyz[3 * f[(i + 1) % 3]];
      CHECK(std::hypot(p[0] - q[0], p[1] - q[1]) <= 6.0 + 1e-9);
    }
  }
}

TEST_CASE("qem's quadrics are the sum of its faces' and its outline edges'", "[core][qem]") {
  // A flat unit square of 2 triangles at z = 5, nothing collapsed.
  core::TriMesh in;
  in.xyz = {0, 0, 5, 1, 0, 5, 1, 1, 5, 0, 1, 5};
  in.faces = {{0, 1, 2}, {0, 2, 3}};
  const core::QemResult r = core::qem_simplify(in, 4);
  REQUIRE(r.quadrics.size() == 4);
  for (std::size_t v = 0; v < 4; ++v) {
    // Zero at the vertex itself: it lies on every plane of its quadric.
    CHECK(r.quadrics[v](&in.xyz[3 * v]) == Approx(0).margin(1e-12));
  }
  // 1 m above vertex 0: its two faces' planes, each weighted by its doubled area squared
  // (1 x 1), give 2; its outline edges' planes are vertical and give nothing.
  const double above[3] = {0, 0, 6};
  CHECK(r.quadrics[0](above) == Approx(2.0));
  // 1 m outside the square's west side, at vertex 0's height: only the west edge's plane
  // (weight 1) sees it.
  const double west[3] = {-1, 0, 5};
  CHECK(r.quadrics[0](west) == Approx(1.0));
}

TEST_CASE("qem's first costs spread over parts give the same mesh as in order", "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  const std::size_t keep = in.vertex_count() / 10;
  const core::QemResult plain = core::qem_simplify(in, keep);
  // Parts of 7 half-edges, last part first: the order a pool of threads might take them in.
  core::QemOptions options;
  std::size_t parts = 0, covered = 0;
  options.for_ranges = [&](std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) {
    const std::size_t count = (n + 6) / 7;
    for (std::size_t i = count; i-- > 0;) {
      const std::size_t end = std::min(n, 7 * i + 7);
      fn(7 * i, end);
      covered += end - 7 * i;
      ++parts;
    }
    CHECK(covered == n);
  };
  const core::QemResult spread = core::qem_simplify(in, keep, options);
  CHECK(parts > 1);
  CHECK(spread.mesh.xyz == plain.mesh.xyz);
  CHECK(spread.mesh.faces == plain.mesh.faces);
  CHECK(spread.source == plain.source);
  CHECK(spread.collapses == plain.collapses);
}

TEST_CASE("qem's full first costs made ahead give the same mesh as walked for in the loop",
          "[core][qem]") {
  const core::TriMesh in = test::hills_mesh();
  core::QemOptions options;
  options.for_ranges = [](std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) {
    for (std::size_t i = (n + 6) / 7; i-- > 0;) fn(7 * i, std::min(n, 7 * i + 7));
  };
  // A fifth of the vertices collapsed (as the piece engine's merge), then nine tenths.
  for (const std::size_t keep : {4 * in.vertex_count() / 5, in.vertex_count() / 10}) {
    INFO("keep " << keep);
    const core::QemResult plain = core::qem_simplify(in, keep, options);
    CHECK(plain.full_costs_taken == 0);
    for (const std::size_t per_collapse : {1, 2, 100}) {
      INFO("full first costs " << per_collapse << " a collapse");
      core::QemOptions ahead = options;
      ahead.full_first_costs = per_collapse;
      const core::QemResult r = core::qem_simplify(in, keep, ahead);
      CHECK(r.full_costs_taken > 0);
      CHECK(r.mesh.xyz == plain.mesh.xyz);
      CHECK(r.mesh.faces == plain.mesh.faces);
      CHECK(r.source == plain.source);
      CHECK(r.collapses == plain.collapses);
      CHECK(r.refused == plain.refused);
    }
  }
}

TEST_CASE("qem refuses an edge of three faces and faces oriented unlike", "[core][qem]") {
  core::TriMesh m;
  // Edge 0-1 with three faces (apexes 2, 3 and 4).
  m.xyz = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 2, 1};
  m.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  CHECK_THROWS_WITH(core::qem_simplify(m, 4), Catch::Contains("more than two faces"));
  // Edge 0-1 run the same way by both its faces.
  m.faces = {{0, 1, 2}, {0, 1, 3}};
  CHECK_THROWS_WITH(core::qem_simplify(m, 3), Catch::Contains("not oriented alike"));
  // Run opposite ways: accepted.
  m.faces = {{0, 1, 2}, {1, 0, 3}};
  CHECK_NOTHROW(core::qem_simplify(m, 4));
}

TEST_CASE("qem with a grid TIN's own pairing of half-edges gives the same mesh", "[core][qem]") {
  // test::hills_mesh (voids, a notch, three-corner squares) with grid_tin's opposites, against
  // qem's own pairing. (Faces reversed by fix_orientation: surface_sampling_test.)
  std::vector<std::uint32_t> opposites;
  const core::TriMesh in = test::hills_mesh(40, 32, &opposites);
  const std::size_t keep = in.vertex_count() / 10;
  const core::QemResult plain = core::qem_simplify(in, keep);
  core::QemOptions options;
  options.opposites = opposites;
  const core::QemResult given = core::qem_simplify(in, keep, options);
  CHECK(given.mesh.xyz == plain.mesh.xyz);
  CHECK(given.mesh.faces == plain.mesh.faces);
  CHECK(given.collapses == plain.collapses);
  // A pairing that does not pair (one pair's half-edges swapped for two of one face) or runs
  // out of step with the faces is refused.
  std::size_t h0 = 0;
  while (opposites[h0] == core::kNoOpposite) ++h0;
  options.opposites = opposites;
  options.opposites[h0] = h0 - h0 % 3 + (h0 % 3 + 1) % 3;
  CHECK_THROWS_WITH(core::qem_simplify(in, keep, options), Catch::Contains("do not pair"));
  options.opposites.assign(opposites.begin(), opposites.end() - 3);
  CHECK_THROWS_WITH(core::qem_simplify(in, keep, options),
                    Catch::Contains("one opposite per half-edge"));
}

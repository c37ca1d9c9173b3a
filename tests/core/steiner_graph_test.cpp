// Steiner-graph geodesics: structure, planar limit, never below the exact geodesic.
#include "core/steiner_graph.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <random>

#include "core/surface_sampling.hpp"
#include "support/exact_geodesic.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

// The grid TIN of z = f(col, row) with `cell` metre cells.
core::TriMesh grid_mesh(int w, int h, double cell, const std::function<double(int, int)>& f) {
  const auto g = test::make_grid(w, h, f);
  const auto t = core::grid_tin(g);
  core::TriMesh m;
  for (auto c : t.cells) {
    m.xyz.insert(m.xyz.end(), {cell * (c % w), -cell * (c / w), g.z[c]});
  }
  m.faces = t.faces;
  core::fix_orientation(m);
  return m;
}

// Textbook Dijkstra on the explicit Steiner graph: every pair of a face's boundary nodes joined,
// no pruning. Distances from source to each target, as GeodesicQuery defines them.
std::vector<double> full_graph_distances(const core::SteinerGraph& g,
                                         const core::SurfacePoint& source,
                                         const std::vector<core::SurfacePoint>& targets) {
  const auto& mesh = g.mesh();
  const std::size_t n = g.node_count();
  auto len = [](const double* a, const double* b) {
    return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                     (a[2] - b[2]) * (a[2] - b[2]));
  };
  std::vector<std::vector<std::uint32_t>> node_faces(n);
  std::vector<std::vector<std::uint32_t>> face_nodes(mesh.faces.size());
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    g.face_nodes(f, face_nodes[f]);
    for (auto v : face_nodes[f]) node_faces[v].push_back(f);
  }
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  const double src[3] = {source.x, source.y, source.z};
  for (auto v : face_nodes[source.face]) {
    dist[v] = len(src, g.position(v));
    heap.push({dist[v], v});
  }
  while (!heap.empty()) {
    const auto [d, u] = heap.top();
    heap.pop();
    if (d > dist[u]) continue;
    for (auto f : node_faces[u]) {
      for (auto v : face_nodes[f]) {
        const double nd = d + len(g.position(u), g.position(v));
        if (nd < dist[v]) {
          dist[v] = nd;
          heap.push({nd, v});
        }
      }
    }
  }
  std::vector<double> out;
  for (const auto& t : targets) {
    const double q[3] = {t.x, t.y, t.z};
    double best = t.face == source.face ? len(src, q) : std::numeric_limits<double>::infinity();
    for (auto v : face_nodes[t.face]) best = std::min(best, dist[v] + len(g.position(v), q));
    out.push_back(best);
  }
  return out;
}

}  // namespace

TEST_CASE("the pruned Dijkstra gives the distances of the full Steiner graph", "[core][geodesic]") {
  // Rough random heights on a grid whose inner vertices are jittered (irregular faces, edges
  // of many lengths, so 0 to 6 Steiner points per edge), with boundary edges.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> height(0.0, 60.0), jitter(-3.0, 3.0);
  const int w = 14, h = 11;
  auto m = grid_mesh(w, h, 10.0, [&](int, int) { return height(rng); });
  for (int r = 1; r + 1 < h; ++r) {
    for (int c = 1; c + 1 < w; ++c) {
      m.xyz[3 * (r * w + c)] += jitter(rng);
      m.xyz[3 * (r * w + c) + 1] += jitter(rng);
    }
  }
  for (double delta : {25.0, 9.0, 4.0}) {
    for (bool buckets : {true, false}) {
      CAPTURE(delta, buckets);
      const core::SteinerGraph g(m, delta);
      core::GeodesicQuery q(g, buckets);
      CHECK(q.uses_buckets() == buckets);
      const auto pts = core::sample_uniform(m, 16, 11);
      std::vector<double> d;
      for (std::size_t i = 0; i < pts.size(); ++i) {
        std::vector<core::SurfacePoint> targets(pts.begin(), pts.end());
        targets.erase(targets.begin() + static_cast<std::ptrdiff_t>(i));
        q.distances(pts[i], targets, d);
        const auto full = full_graph_distances(g, pts[i], targets);
        for (std::size_t j = 0; j < targets.size(); ++j) {
          CAPTURE(i, j);
          CHECK(d[j] == Approx(full[j]).epsilon(1e-12));
        }
      }
    }
  }
}

TEST_CASE("targets beside graph nodes get their full-graph distance from the buckets",
          "[core][geodesic]") {
  // A target's last segment can be far shorter than a bucket is wide: a node settled after the
  // target in the same bucket may still lower it. Targets 1 cm from a face's boundary nodes,
  // towards its centroid (so on the face), many to a face.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> height(0.0, 40.0);
  const auto m = grid_mesh(12, 10, 10.0, [&](int, int) { return height(rng); });
  const core::SteinerGraph g(m, 3.0);
  core::GeodesicQuery q(g);
  REQUIRE(q.uses_buckets());
  std::vector<core::SurfacePoint> targets;
  std::vector<std::uint32_t> nodes;
  for (std::uint32_t f = 0; f < m.faces.size(); f += 7) {
    double c[3] = {0, 0, 0};
    for (auto v : m.faces[f]) {
      for (int k = 0; k < 3; ++k) c[k] += m.xyz[3 * v + k] / 3;
    }
    g.face_nodes(f, nodes);
    for (auto v : nodes) {
      const double* p = g.position(v);
      const double t = 0.01 / std::sqrt((c[0] - p[0]) * (c[0] - p[0]) +
                                        (c[1] - p[1]) * (c[1] - p[1]) +
                                        (c[2] - p[2]) * (c[2] - p[2]));
      targets.push_back({p[0] + t * (c[0] - p[0]), p[1] + t * (c[1] - p[1]),
                         p[2] + t * (c[2] - p[2]), f});
    }
  }
  const auto sources = core::sample_uniform(m, 6, 2);
  std::vector<double> d;
  for (const auto& source : sources) {
    q.distances(source, targets, d);
    const auto full = full_graph_distances(g, source, targets);
    for (std::size_t j = 0; j < targets.size(); ++j) {
      CAPTURE(j);
      CHECK(d[j] == Approx(full[j]).epsilon(1e-12));
    }
  }
}

TEST_CASE("segment bounds: Dial's buckets only where no face is degenerate", "[core][geodesic]") {
  // A right triangle with legs 4 and 3 (hypotenuse 5), delta 2: 2, 1 and 2 Steiner points,
  // spacings 4/3, 3/2 and 5/3. Bound per corner: min of its two spacings times min(1, sin):
  // right angle 4/3; at (4,0) (sin 3/5) 4/3 * 0.6 = 0.8; at (0,3) (sin 4/5) 1.5 * 0.8 = 1.2.
  // (The true shortest segment there is 1: (8/3,0) to (8/3,1).)
  core::TriMesh m;
  m.xyz = {0, 0, 0, 4, 0, 0, 0, 3, 0};
  m.faces = {{0, 1, 2}};
  const core::SteinerGraph g(m, 2.0);
  CHECK(g.steiner_count() == 5);
  CHECK(g.max_segment() == Approx(5.0));
  CHECK(g.min_segment() == Approx(0.8));
  CHECK(core::GeodesicQuery(g).uses_buckets());
  // A flat (zero-angle) face: no positive bound, so the heap.
  core::TriMesh flat;
  flat.xyz = {0, 0, 0, 4, 0, 0, 8, 0, 0};
  flat.faces = {{0, 1, 2}};
  const core::SteinerGraph gf(flat, 2.0);
  CHECK(gf.min_segment() == 0);
  CHECK_FALSE(core::GeodesicQuery(gf).uses_buckets());
}

TEST_CASE("Steiner points: floor(len / delta) inside every edge", "[core][geodesic]") {
  // One unit square split in two: 4 edges of length 1, a diagonal of sqrt(2).
  core::TriMesh m;
  m.xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  m.faces = {{0, 1, 3}, {0, 3, 2}};
  const core::SteinerGraph g(m, 0.3);
  // floor(1 / 0.3) = 3 per side, floor(1.414 / 0.3) = 4 on the diagonal.
  CHECK(g.steiner_count() == 4 * 3 + 4);
  std::vector<std::uint32_t> nodes;
  g.face_nodes(0, nodes);
  CHECK(nodes.size() == 3 + 3 + 3 + 4);
  CHECK(core::mean_edge_length(m) == Approx((4 + std::sqrt(2.0)) / 5));
}

TEST_CASE("on a plane, Steiner distances approach the Euclidean distance as delta shrinks",
          "[core][geodesic]") {
  const auto m = grid_mesh(20, 20, 10.0, [](int c, int r) { return 3.0 * c - 2.0 * r; });
  const auto pts = core::sample_uniform(m, 12, 3);
  double previous = 1e9;
  for (double delta : {10.0, 5.0, 2.5, 1.25}) {
    const core::SteinerGraph g(m, delta);
    core::GeodesicQuery q(g);
    double sum = 0;
    int n = 0;
    std::vector<double> d;
    for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
      std::vector<core::SurfacePoint> targets(pts.begin() + i + 1, pts.end());
      q.distances(pts[i], targets, d);
      for (std::size_t j = 0; j < targets.size(); ++j) {
        const double e =
            std::sqrt(std::pow(pts[i].x - targets[j].x, 2) + std::pow(pts[i].y - targets[j].y, 2) +
                      std::pow(pts[i].z - targets[j].z, 2));
        CHECK(d[j] >= e * (1 - 1e-12));  // never shorter than the straight line
        sum += (d[j] - e) / e;
        ++n;
      }
    }
    const double mean = sum / n;
    CHECK(mean < previous);
    previous = mean;
  }
  CHECK(previous < 0.01);
}

TEST_CASE("two points in one face are joined by their straight segment", "[core][geodesic]") {
  core::TriMesh m;
  m.xyz = {0, 0, 0, 10, 0, 0, 0, 10, 0};
  m.faces = {{0, 1, 2}};
  const core::SteinerGraph g(m, 100.0);
  core::GeodesicQuery q(g);
  std::vector<double> d;
  q.distances({1, 1, 0, 0}, {{4, 5, 0, 0}}, d);
  CHECK(d[0] == Approx(5.0));
}

TEST_CASE("Steiner distances are never below the exact geodesic and within 1 % on average",
          "[core][geodesic][exact]") {
  // Rough synthetic hills, 30 x 30 cells of 30 m; CGAL's exact geodesics as reference.
  const auto m = grid_mesh(30, 30, 30.0, [](int c, int r) {
    return 40.0 * std::sin(c * 0.45) * std::cos(r * 0.35) + 15.0 * std::sin(c * 1.3 + r * 0.7);
  });
  const double delta = 0.25 * core::mean_edge_length(m);
  const auto fig = test::steiner_accuracy(m, delta, 4, 20, 5);
  CHECK(fig.pairs == 80);
  CHECK(fig.min_rel > -1e-9);
  CHECK(fig.mean_rel < 0.01);
}

TEST_CASE("PointLocator copes with flat and thin meshes and far points", "[steiner][robust]") {
  // All vertices on one line (zero-area bounding box): found by the fuzzer, it overflowed the
  // bucket grid. Now the buckets stay few and queries answer.
  core::TriMesh flat;
  flat.xyz = {0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0, 0};
  flat.faces = {{0, 1, 2}, {1, 2, 3}};
  const core::PointLocator on_line(flat);
  CHECK_NOTHROW(on_line.locate(1e300, -1e300, 1e300));
  CHECK_FALSE(on_line.locate(0.5, 7.0, 0.25).has_value());
  // A 1 x 1e9 sliver: a point inside is found, a point far away is not, even with a snap.
  core::TriMesh thin;
  thin.xyz = {0, 0, 1, 1e9, 0, 2, 0, 1, 3};
  thin.faces = {{0, 1, 2}};
  const core::PointLocator sliver(thin);
  const auto inside = sliver.locate(10.0, 0.5);
  REQUIRE(inside.has_value());
  CHECK_FALSE(inside->snapped);
  CHECK_FALSE(sliver.locate(10.0, 1e6, 1.0).has_value());
  CHECK(sliver.locate(10.0, 1.5, 1.0).has_value());
}

TEST_CASE("a vertex's total angle: its corners' sum in one closed fan, -1 on the outline",
          "[core][geodesic]") {
  constexpr double kPi = 3.14159265358979323846;
  SECTION("a 16-sided pyramid: the apex's angle is 16 times its faces' angle") {
    const int n = 16;
    const double radius = 100, height = 70;
    const core::TriMesh m = test::pyramid_mesh(n, radius, height);
    core::SteinerGraph g(m, 20.0);
    CHECK(std::isnan(g.vertex_angle(0)));  // not kept yet
    g.keep_vertex_angles();
    const double slant = std::hypot(radius, height);
    const double beta = 2 * std::asin(radius * std::sin(kPi / n) / slant);
    CHECK(g.vertex_angle(0) == Approx(n * beta).epsilon(1e-12));
    CHECK(g.vertex_angle(0) < 2 * kPi);
    for (std::uint32_t v = 1; v <= n; ++v) CHECK(g.vertex_angle(v) == -1);
  }
  SECTION("a plane's interior vertices: 2 pi; its outline's: -1") {
    const auto m = grid_mesh(5, 4, 10.0, [](int c, int r) { return 3.0 * c - 2.0 * r; });
    core::SteinerGraph g(m, 5.0);
    g.keep_vertex_angles();
    for (std::uint32_t v = 0; v < m.vertex_count(); ++v) {
      const std::uint32_t c = v % 5, r = v / 5;
      const bool outline = c == 0 || c == 4 || r == 0 || r == 3;
      CAPTURE(v);
      if (outline) {
        CHECK(g.vertex_angle(v) == -1);
      } else {
        CHECK(g.vertex_angle(v) == Approx(2 * kPi).epsilon(1e-12));
      }
    }
  }
  SECTION("two fans meeting at a vertex: none kept (the caller walks its own)") {
    // Two square cones of four faces each, apex to apex at vertex 0 (a double cone): each
    // fan is closed, and neither holds all of vertex 0's faces.
    core::TriMesh m;
    m.xyz = {0, 0, 0};
    for (int k = 0; k < 2; ++k) {
      const double z = k == 0 ? 10 : -10;
      for (int i = 0; i < 4; ++i) {
        m.xyz.insert(m.xyz.end(), {10 * std::cos(kPi * i / 2), 10 * std::sin(kPi * i / 2), z});
      }
    }
    for (std::uint32_t i = 0; i < 4; ++i) m.faces.push_back({0, 1 + i, 1 + (i + 1) % 4});
    for (std::uint32_t i = 0; i < 4; ++i) m.faces.push_back({0, 5 + (i + 1) % 4, 5 + i});
    core::SteinerGraph g(m, 5.0);
    g.keep_vertex_angles();
    CHECK(std::isnan(g.vertex_angle(0)));
    CHECK(g.vertex_angle(1) == -1);
  }
}

TEST_CASE("vertices in Z order: the same faces over the same points, the same distances",
          "[core][geodesic]") {
  const int w = 8, h = 8;
  const double cell = 10;
  const auto f = [](int c, int r) { return 3.0 * std::sin(0.7 * c) + 2.0 * std::cos(0.5 * r); };
  const core::TriMesh rows = grid_mesh(w, h, cell, f);
  core::TriMesh z = rows;
  core::order_vertices_spatially(z);
  REQUIRE(z.vertex_count() == rows.vertex_count());
  REQUIRE(z.faces.size() == rows.faces.size());
  for (std::size_t i = 0; i < rows.faces.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) {
        REQUIRE(z.xyz[3 * z.faces[i][k] + c] == rows.xyz[3 * rows.faces[i][k] + c]);
      }
    }
  }
  // Z order from the lowest x, y: the first four vertices are the 2 x 2 cells there (rows run
  // downwards in y: the last two rows), the next four the block beside them in x.
  const double y0 = -cell * (h - 1);
  for (std::size_t v = 0; v < 8; ++v) {
    const double x = z.xyz[3 * v], y = z.xyz[3 * v + 1];
    CHECK(x == (v < 4 ? 0.0 : 2 * cell) + cell * static_cast<double>(v % 2));
    CHECK(y == y0 + cell * static_cast<double>((v / 2) % 2));
  }
  // The same surface: the same geodesics between the same points.
  const auto points = core::sample_uniform(rows, 6, 5);
  const auto points_z = core::sample_uniform(z, 6, 5);
  const std::vector<core::SurfacePoint> targets(points.begin() + 1, points.end());
  const std::vector<core::SurfacePoint> targets_z(points_z.begin() + 1, points_z.end());
  core::SteinerGraph g_rows(rows, 4.0), g_z(z, 4.0);
  for (const bool anchored : {false, true}) {
    core::GeodesicQuery q_rows(g_rows), q_z(g_z);
    q_rows.set_anchored(anchored);
    q_z.set_anchored(anchored);
    std::vector<double> d_rows, d_z;
    q_rows.distances(points[0], targets, d_rows);
    q_z.distances(points_z[0], targets_z, d_z);
    for (std::size_t j = 0; j < targets.size(); ++j) {
      CHECK(points_z[j + 1].x == points[j + 1].x);
      CHECK(d_z[j] == Approx(d_rows[j]).epsilon(1e-6));
    }
  }
}

// QSlim baseline: exact count, the outline locked, no folds, the footprint covered once.
#include "core/qslim.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/surface_sampling.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Hills with a void, a notch and a cut corner; vertices at (col, -row) so faces are
// counter-clockwise after fix_orientation.
core::TriMesh hills_mesh(int w = 40, int h = 32) {
  const auto g = test::make_grid(w, h, [w, h](int c, int r) {
    if (std::hypot(c - 12.0, r - 14.0) < 4.0) return kNaN;
    if (c >= w - 6 && r >= h / 2 - 2 && r <= h / 2 + 2) return kNaN;
    if (c + r < 3) return kNaN;
    return 10.0 * std::sin(c * 0.3) * std::cos(r * 0.25) + 0.3 * c;
  });
  const core::GridTin tin = core::grid_tin(g);
  core::TriMesh m;
  for (std::uint32_t cell : tin.cells) {
    const double c = cell % static_cast<std::uint32_t>(w), r = cell / static_cast<std::uint32_t>(w);
    m.xyz.insert(m.xyz.end(), {c, -r, g.z[cell]});
  }
  m.faces = tin.faces;
  core::fix_orientation(m);
  return m;
}

// Positions (x, y) of the vertices on the mesh's border.
std::set<std::pair<double, double>> border(const core::TriMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const auto& f : m.faces) {
    for (int i = 0; i < 3; ++i) {
      const auto a = f[i], b = f[(i + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  }
  std::set<std::pair<double, double>> out;
  for (const auto& [e, n] : uses) {
    if (n != 1) continue;
    for (auto v : {e.first, e.second}) out.insert({m.xyz[3 * v], m.xyz[3 * v + 1]});
  }
  return out;
}

}  // namespace

TEST_CASE("QSlim keeps the count, the outline, and a height field", "[core][qslim]") {
  const core::TriMesh in = hills_mesh();
  const auto in_border = border(in);
  const double in_area = core::mesh_area(core::xy_of(in.xyz), in.faces);
  for (std::size_t keep : {in.vertex_count() / 2, in.vertex_count() / 5}) {
    core::QslimStats stats;
    const core::TriMesh out = core::qslim(in, keep, &stats);
    CHECK(out.vertex_count() == keep);
    CHECK(stats.kept_vertices == keep);
    const core::MeshCheck mc = core::check_mesh(core::xy_of(out.xyz), out.faces);
    CHECK(mc.clockwise_or_flat == 0);
    CHECK(mc.bad_edges == 0);
    CHECK(mc.area == Approx(in_area).epsilon(1e-12));
    // The border is the same polygon: same vertices at the same places.
    CHECK(border(out) == in_border);
  }
}

TEST_CASE("QSlim cannot go below the locked outline", "[core][qslim]") {
  const core::TriMesh in = hills_mesh();
  const std::size_t outline = border(in).size();
  core::QslimStats stats;
  const core::TriMesh out = core::qslim(in, 3, &stats);
  CHECK(out.vertex_count() >= outline);
  CHECK(out.vertex_count() < outline + outline / 2);
  CHECK(stats.rejected_folds > 0);
}

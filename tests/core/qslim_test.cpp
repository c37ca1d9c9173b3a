// QSlim baseline: exact count, the outline locked, no folds, the footprint covered once.
#include "core/qslim.hpp"

#include <catch2/catch.hpp>
#include <cmath>

#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/surface_sampling.hpp"
#include "test_support.hpp"

using namespace dpts;

TEST_CASE("QSlim keeps the count, the outline, and a height field", "[core][qslim]") {
  const core::TriMesh in = test::hills_mesh();
  const auto in_border = test::border_points(in);
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
    CHECK(test::border_points(out) == in_border);
  }
}

TEST_CASE("QSlim cannot go below the locked outline", "[core][qslim]") {
  const core::TriMesh in = test::hills_mesh();
  const std::size_t outline = test::border_points(in).size();
  core::QslimStats stats;
  const core::TriMesh out = core::qslim(in, 3, &stats);
  CHECK(out.vertex_count() >= outline);
  CHECK(out.vertex_count() < outline + outline / 2);
  CHECK(stats.rejected_folds > 0);
}

TEST_CASE("QSlim's plane quadrics reproduce a roof exactly", "[core][qslim]") {
  // Two planes meeting along a ridge (y = 12): every collapse within one plane, or along the
  // ridge, costs nothing, so down to a few interior vertices the surface is unchanged.
  const int w = 30, h = 25;
  const auto g = test::make_grid(w, h, [](int c, int r) {
    return 5.0 + 0.3 * c + (r <= 12 ? 0.8 * r : 0.8 * 12 - 0.5 * (r - 12));
  });
  const core::Tin tin = core::grid_tin(g);
  core::TriMesh in;
  for (std::uint32_t cell : tin.cells) {
    in.xyz.insert(in.xyz.end(),
                  {static_cast<double>(cell % w), static_cast<double>(cell / w), g.z[cell]});
  }
  in.faces = tin.faces;
  core::fix_orientation(in);
  const std::size_t outline = test::border_points(in).size();
  const core::TriMesh out = core::qslim(in, outline + 4);
  CHECK(out.vertex_count() == outline + 4);
  const core::PointLocator locate(out);
  for (std::size_t v = 0; v < in.vertex_count(); ++v) {
    const auto hit = locate.locate(in.xyz[3 * v], in.xyz[3 * v + 1]);
    REQUIRE(hit);
    CHECK(hit->point.z == Approx(in.xyz[3 * v + 2]).margin(1e-9));
  }
}

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

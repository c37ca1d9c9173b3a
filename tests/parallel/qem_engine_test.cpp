// qem's piece engine: the exact count, the footprint covered once across piece seams (no
// crack, no overlap, no vertex twice), no fold in the output CRS also for a reprojected DEM,
// and the same mesh for any thread count.
#include "parallel/qem_engine.hpp"

#include <gdal_priv.h>
#include <tbb/global_control.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <mutex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/mesh_check.hpp"
#include "core/qem.hpp"
#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

struct Fixture {
  test::TempDir dir;
  std::string path = (dir / "hills.tif").string();
  io::DemInfo info;
  double area = 0;           // the full-resolution TIN's, in the output CRS
  double outline = 0;        // and the length of its boundary there
  std::size_t vertices = 0;  // and its vertices
  explicit Fixture(bool geographic) {
    GDALAllRegister();
    if (geographic) {
      // 1 degree by 0.8 at 48 N: the grid lines bend in UTM.
      test::write_geotiff(path, test::hills_with_voids(), {-124.0, 1.0 / 96, 0, 48.8, 0, -0.8 / 80},
                          "EPSG:4326");
    } else {
      test::write_geotiff(path, test::hills_with_voids(), {500000, 30, 0, 4100000, 0, -30}, "");
    }
    info = io::open_dem(path, {});
    const core::TriMesh full = io::read_dem(path, {}, nullptr).grid_mesh();
    const core::MeshCheck mc = core::check_mesh(core::xy_of(full.xyz), full.faces);
    area = mc.area;
    outline = mc.boundary_length;
    vertices = full.vertex_count();
  }
};

// A tile of 64 kB: the merge takes the pieces a group at a time (several groups), unless
// merge_bytes lets one group hold them all.
par::QemEngineOptions options(std::size_t keep, std::size_t merge_bytes = 0) {
  par::QemEngineOptions o;
  o.keep.vertices = keep;
  o.levels = 4;
  o.tile_bytes = 64 << 10;
  o.merge_bytes = merge_bytes;
  o.premerge_vertices = 0;  // the pre-merge, where one group holds all the pieces
  return o;
}

void check_cover(const core::TriMesh& m, const Fixture& fx) {
  const core::MeshCheck mc = core::check_mesh(core::xy_of(m.xyz), m.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
  CHECK(mc.area == Approx(fx.area).epsilon(1e-6));
  // No crack: the boundary is the outline (a seam left open would add twice its length; a
  // reprojected outline's straight runs become chords, shorter by far less).
  CHECK(mc.boundary_length == Approx(fx.outline).epsilon(1e-5));
  // A seam vertex stitched once: no two vertices at one place.
  std::set<std::pair<double, double>> at;
  for (std::size_t v = 0; v < m.vertex_count(); ++v) at.insert({m.xyz[3 * v], m.xyz[3 * v + 1]});
  CHECK(at.size() == m.vertex_count());
}

}  // namespace

TEST_CASE("qem's piece engine keeps the count and covers the footprint once across seams",
          "[parallel][qem]") {
  const bool geographic = GENERATE(false, true);
  const std::size_t merge_bytes = GENERATE(std::size_t{0}, std::size_t{1} << 30);
  INFO((geographic ? "geographic" : "projected") << ", merge bytes " << merge_bytes);
  Fixture fx(geographic);
  for (double share : {0.3, 0.1}) {
    par::MetaStats stats;
    const std::size_t keep = static_cast<std::size_t>(share * 6000);
    const core::TriMesh m =
        par::simplify_qem(io::GdalRaster(fx.info), options(keep, merge_bytes), nullptr, &stats);
    CHECK(stats.pieces.size() >= 16);
    // One group, or several: the kept vertices of the pieces (700 bytes each at 1.3 x the
    // share) do not fit 64 kB.
    std::vector<core::Piece> pieces;
    for (const auto& p : stats.pieces) pieces.push_back(p.piece);
    const auto groups = par::qem_groups(pieces, share, options(keep, merge_bytes));
    CHECK(groups.front() == 0);
    CHECK(groups.back() == pieces.size());
    if (merge_bytes) {
      CHECK(groups.size() == 2);
      // One group: runs of its pieces collapsed some of the way first, concurrently.
      CHECK(stats.premerge_collapses > 0);
    } else {
      CHECK(groups.size() > 4);
      CHECK(stats.premerge_collapses == 0);
    }
    CHECK(m.vertex_count() == keep);
    CHECK(stats.kept_vertices == keep);
    std::size_t kept = 0;
    for (const auto& p : stats.pieces) kept += p.kept;
    CHECK(kept > keep);  // the pieces leave the merge a choice
    // Every vertex near the surface: its height within the DEM's range (80 to 232 m), give
    // or take what an optimal placement may overshoot.
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
      CHECK(m.xyz[3 * v + 2] > 70.0);
      CHECK(m.xyz[3 * v + 2] < 245.0);
    }
    // In the output CRS: a reprojected DEM's mesh must not fold there either.
    check_cover(m, fx);
  }
}

// The merge of a group holds the cells of later pieces its windows reach (full resolution,
// locked); they are in those pieces' share, not in this group's. Counted in both, a DEM of
// several groups kept too few at --keep 100 % (the first groups collapsed as many of their
// own vertices as they held of the next ones').
TEST_CASE("qem's piece engine keeps every vertex at 100 % over several groups", "[parallel][qem]") {
  const bool geographic = GENERATE(false, true);
  INFO((geographic ? "geographic" : "projected"));
  Fixture fx(geographic);
  const std::size_t all = fx.vertices;
  for (const std::size_t keep : {all, all - all / 200}) {
    INFO("keep " << keep << " of " << all);
    par::MetaStats stats;
    const core::TriMesh m =
        par::simplify_qem(io::GdalRaster(fx.info), options(keep), nullptr, &stats);
    std::vector<core::Piece> pieces;
    for (const auto& p : stats.pieces) pieces.push_back(p.piece);
    CHECK(par::qem_groups(pieces, 1.0, options(keep)).size() > 4);
    CHECK(stats.input_vertices == all);
    CHECK(m.vertex_count() == keep);
    check_cover(m, fx);
  }
}

// A piece whose voids' outlines alone held more vertices than its share by size once collapsed
// everything else it could, at any cost: the hills beside a sea of one-cell voids (as
// kilauea_utm5's coast) went flat, 9.6 m off (vertical RMSE 0.77 m, where one collapse of the
// whole grid gives 0.47 and 4.8 m). With the pilot's cost bound each piece keeps what its
// surface needs: 0.46-0.51 m, at most 4.0-4.8 m.
TEST_CASE("qem's piece engine keeps hills beside voids whose outlines fill a piece's share",
          "[parallel][qem]") {
  const std::size_t merge_bytes = GENERATE(std::size_t{0}, std::size_t{1} << 30);
  INFO("merge bytes " << merge_bytes);
  test::TempDir dir;
  const std::string path = (dir / "coast.tif").string();
  // West: a gentle plain. East: hills, and south of them a sea of one-cell voids among cells
  // at 0 m (every third cell a void).
  const int w = 128, h = 96;
  const core::HeightGrid grid = test::make_grid(w, h, [](int c, int r) {
    if (c < 64) return 50.0 + 0.2 * c + 0.1 * r;
    if (r >= 56) return (c + 2 * r) % 3 == 0 ? std::nan("") : 0.0;
    return 100.0 + 40.0 * std::sin(c * 0.35) * std::cos(r * 0.3);
  });
  GDALAllRegister();
  test::write_geotiff(path, grid, {500000, 30, 0, 4100000, 0, -30}, "");
  const io::DemInfo info = io::open_dem(path, {});
  const core::TriMesh full = io::read_dem(path, {}, nullptr).grid_mesh();
  const std::size_t keep = full.vertex_count() / 10;
  // The vertical error at every cell centre of the grid TIN.
  auto error = [&](const core::TriMesh& m) {
    const core::PointLocator at(m);
    double sq = 0, most = 0;
    for (std::size_t v = 0; v < full.vertex_count(); ++v) {
      const auto hit = at.locate(full.xyz[3 * v], full.xyz[3 * v + 1], 1e-6);
      REQUIRE(hit);
      const double dz = hit->point.z - full.xyz[3 * v + 2];
      sq += dz * dz;
      most = std::max(most, std::fabs(dz));
    }
    return std::pair{std::sqrt(sq / static_cast<double>(full.vertex_count())), most};
  };
  const auto whole = error(core::qem_simplify(full, keep).mesh);
  par::MetaStats stats;
  const core::TriMesh m =
      par::simplify_qem(io::GdalRaster(info), options(keep, merge_bytes), nullptr, &stats);
  REQUIRE(m.vertex_count() == keep);
  CHECK(stats.pieces.size() >= 16);
  CHECK(stats.pilot_pieces >= 8);
  CHECK(stats.piece_cost_bound >= 0);
  const auto pieces = error(m);
  INFO("RMSE " << pieces.first << " m, max " << pieces.second << " m; whole grid " << whole.first
               << ", " << whole.second);
  CHECK(pieces.first < 1.5 * whole.first);
  CHECK(pieces.second < 2.0 * whole.second);
}

TEST_CASE("qem's groups share the target by what their pieces keep, voids' outlines counted",
          "[parallel][qem]") {
  test::TempDir dir;
  const std::string path = (dir / "sea.tif").string();
  // Hills, and east of them (the last pieces in k-d order) a sea of voids scattered among
  // cells at 0 m (a third of its cells): a piece of it keeps several times what a piece of
  // hills does, all outline.
  const int w = 240, h = 120;
  const core::HeightGrid grid = test::make_grid(w, h, [](int c, int r) {
    if (c >= 210) {
      const std::uint32_t hash = (static_cast<std::uint32_t>(c) * 73856093u) ^
                                 (static_cast<std::uint32_t>(r) * 19349663u);
      return (hash >> 7) % 3 == 0 ? std::nan("") : 0.0;
    }
    return 100.0 + 40.0 * std::sin(c * 0.11) * std::cos(r * 0.13) + 0.05 * c;
  });
  GDALAllRegister();
  test::write_geotiff(path, grid, {500000, 30, 0, 4100000, 0, -30}, "");
  const io::DemInfo info = io::open_dem(path, {});
  const std::size_t keep = 3000;
  par::QemEngineOptions o = options(keep, std::size_t{64} << 10);
  o.tile_bytes = std::size_t{1} << 20;
  par::MetaStats stats;
  const core::TriMesh m = par::simplify_qem(io::GdalRaster(info), o, nullptr, &stats);
  INFO("groups " << stats.merge_groups << ", kept per inner vertex "
                 << stats.pilot_kept_per_inner << ", per outline vertex "
                 << stats.pilot_kept_per_outline << ", forced " << stats.pilot_forced_per_outline
                 << "; kept " << m.vertex_count());
  REQUIRE(stats.merge_groups > 3);
  CHECK(stats.piece_cost_bound >= 0);
  CHECK(stats.pilot_kept_per_outline > 2 * stats.pilot_kept_per_inner);
  CHECK(stats.pilot_forced_per_outline > 0);
  // The target reached: the sea's groups were asked what their outlines hold, the others the
  // rest (shared by the count of all kept: 3,203).
  CHECK(m.vertex_count() <= keep + keep / 100);
}

TEST_CASE("qem's pilot finishes its pieces as the pieces' stage would", "[parallel][qem]") {
  Fixture fx(false);
  const std::size_t merge_bytes = GENERATE(std::size_t{64} << 10, std::size_t{1} << 30);
  const std::size_t keep = GENERATE(std::size_t{600}, std::size_t{3000});
  INFO("merge bytes " << merge_bytes << ", keep " << keep);
  const io::GdalRaster dem(fx.info);
  // A tile of 1 MB: room for several copies of the pilot's pieces' collapses (of 16 pieces).
  par::QemEngineOptions o = options(keep, merge_bytes);
  o.tile_bytes = std::size_t{1} << 20;
  par::MetaStats a;
  const core::TriMesh finished = par::simplify_qem(dem, o, nullptr, &a);
  CHECK(a.pilot_pieces >= 8);
  CHECK(a.pilot_finished >= 4);
  if (merge_bytes < o.tile_bytes) CHECK(a.merge_groups > 1);
  CHECK(a.pilot_finished <= a.pilot_pieces);
  // The stages without the pilot's outputs: every piece simplified in stage 2.
  par::MetaStats b;
  const std::vector<core::Piece> pieces = par::plan_qem(dem, o, nullptr, b);
  std::size_t marked = 0;
  for (const par::PieceReport& r : b.pieces) marked += r.by_pilot ? 1 : 0;
  CHECK(marked == 0);
  std::vector<std::size_t> all(pieces.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  std::vector<par::QemPieceMesh> outputs;
  par::simplify_qem_pieces(dem, o, pieces, all, b, outputs, nullptr);
  const core::TriMesh again = par::merge_qem(dem, o, pieces, outputs, b, nullptr);
  CHECK(a.piece_cost_bound == b.piece_cost_bound);
  CHECK(finished.xyz == again.xyz);
  CHECK(finished.faces == again.faces);
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    INFO("piece " << i);
    CHECK(a.pieces[i].kept == b.pieces[i].kept);
  }
}

TEST_CASE("qem's piece engine gives the same mesh for 1, 2 and 4 threads",
          "[parallel][qem][determinism]") {
  Fixture fx(false);
  const std::size_t merge_bytes = GENERATE(std::size_t{0}, std::size_t{1} << 30);
  auto run = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism,
                          static_cast<std::size_t>(threads));
    return par::simplify_qem(io::GdalRaster(fx.info), options(600, merge_bytes), nullptr);
  };
  const core::TriMesh a = run(1);
  for (int threads : {2, 4}) {
    const core::TriMesh b = run(threads);
    CHECK(a.xyz == b.xyz);
    CHECK(a.faces == b.faces);
  }
}

TEST_CASE("qem's piece engine stops when asked, also during a merge beside the next pieces",
          "[parallel][qem]") {
  Fixture fx(false);
  tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
  // Groups of 64 kB, pieces in tiles of 1 MB: room for copies of the pilot's collapses.
  par::QemEngineOptions o = options(600, std::size_t{64} << 10);
  o.tile_bytes = std::size_t{1} << 20;
  // One run reporting: "simplify" while a group's merge runs beside the next group's pieces
  // (never falling), then "merge", the last group's.
  std::vector<std::pair<std::string, double>> calls;
  std::mutex m;
  const core::Progress record = [&](double f, std::string_view stage) {
    std::lock_guard<std::mutex> hold(m);
    calls.emplace_back(std::string(stage), f);
    return true;
  };
  par::MetaStats stats;
  par::simplify_qem(io::GdalRaster(fx.info), o, record, &stats);
  std::vector<core::Piece> pieces;
  for (const auto& p : stats.pieces) pieces.push_back(p.piece);
  REQUIRE(par::qem_groups(pieces, 600.0 / 6000, o).size() > 3);  // several groups
  bool merging = false;
  double last = 0;
  for (const auto& [stage, f] : calls) {
    if (stage == "merge") merging = true;
    if (stage == "simplify") {
      CHECK_FALSE(merging);
      CHECK(f >= last);
      last = f;
    }
  }
  CHECK(merging);
  // Stopped at any call, it stops: the task merging beside the pieces is waited for; and at
  // each of the pilot's (its pieces' collapses, then the copies going on to their outputs).
  const std::size_t n = calls.size();
  std::vector<std::size_t> stops = {1, n / 4, n / 2, 3 * n / 4, n - 1};
  std::size_t pilot_calls = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (calls[k].first != "pilot") continue;
    stops.push_back(k + 1);
    ++pilot_calls;
  }
  CHECK(pilot_calls >= stats.pilot_pieces);
  CHECK(stats.pilot_finished > 0);
  for (const std::size_t stop : stops) {
    INFO("stop at call " << stop << " of " << n);
    std::size_t seen = 0;
    const core::Progress ask = [&](double, std::string_view) {
      std::lock_guard<std::mutex> hold(m);
      return ++seen < stop;
    };
    CHECK_THROWS_AS(par::simplify_qem(io::GdalRaster(fx.info), o, ask), Cancelled);
  }
}

TEST_CASE("the engines read a grid in memory as they read it from GDAL", "[parallel][qem][meta]") {
  Fixture fx(false);
  const core::HeightGrid grid = io::read_dem(fx.path, {}, nullptr).grid;
  const core::MemoryRaster memory(grid, fx.info.frame, "hills");
  CHECK(memory.width() == 96);
  CHECK(memory.height() == 80);
  // qem: the same faces; vertices moved by the geotransform's offset (cell centres), the
  // memory source's output coordinates being the frame's in metres.
  const core::TriMesh a = par::simplify_qem(io::GdalRaster(fx.info), options(600), nullptr);
  const core::TriMesh b = par::simplify_qem(memory, options(600), nullptr);
  REQUIRE(a.vertex_count() == 600);
  REQUIRE(b.vertex_count() == 600);
  CHECK(a.faces == b.faces);
  for (std::size_t v = 0; v < a.vertex_count(); ++v) {
    CHECK(a.xyz[3 * v] - b.xyz[3 * v] == 500015.0);
    CHECK(a.xyz[3 * v + 1] - b.xyz[3 * v + 1] == 4099985.0);
    CHECK(a.xyz[3 * v + 2] == b.xyz[3 * v + 2]);
  }
  // The meta engine: the same kept cells and faces.
  par::MetaOptions mo;
  mo.keep.vertices = 600;
  mo.tile_bytes = 64 << 10;
  mo.value_points = 8;
  const par::MetaResult ma = par::simplify_meta(io::GdalRaster(fx.info), mo, nullptr);
  const par::MetaResult mb = par::simplify_meta(memory, mo, nullptr);
  CHECK(ma.tin.cells.size() == 600);
  CHECK(ma.tin.cells == mb.tin.cells);
  CHECK(ma.tin.faces == mb.tin.faces);
  CHECK(ma.z == mb.z);
  // A window outside the grid is refused.
  CHECK_THROWS_AS(memory.read(90, 0, 10, 1), std::out_of_range);
}

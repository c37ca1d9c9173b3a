// The engine on real DEMs from ../shared/data (built only when that folder exists).
#include <gdal_priv.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <set>

#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/qem.hpp"
#include "core/qslim.hpp"
#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"
#include "parallel/meta.hpp"
#include "parallel/simplify.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

struct Result {
  io::Dem dem;
  core::Tin tin;
  par::SimplifyStats stats;
};

Result simplify_file(const std::string& name, core::Importance kind, double percent) {
  GDALAllRegister();
  Result r{io::read_dem(test::shared_data(name), {}, nullptr), {}, {}};
  core::EliminationOptions opt;
  opt.importance = kind;
  par::KeepTarget target;
  target.percent = percent;
  r.tin = par::simplify_dem(r.dem.grid, r.dem.frame, opt, target, nullptr, &r.stats);
  return r;
}

}  // namespace

TEST_CASE("St Helens at 10 %: exact count, counter-clockwise faces, footprint covered once",
          "[shared][simplify]") {
  const auto kind = GENERATE(core::Importance::vp, core::Importance::pld);
  const Result r = simplify_file("st_helens_crater.tif", kind, 10.0);
  CHECK(r.stats.input_vertices == 128 * 128);
  CHECK(r.tin.cells.size() == 1638);  // round(0.1 x 16384)
  const auto xy = r.dem.output_xy(r.tin.cells);
  const core::MeshCheck mc = core::check_mesh(xy, r.tin.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
  // The cell-centre rectangle: 127 x 127 cells of 30 m.
  CHECK(mc.area == Approx(127.0 * 30 * 127 * 30).epsilon(1e-12));
}

TEST_CASE("St Helens at 10 % with VP' and PLD': exact count, footprint covered once",
          "[shared][meta]") {
  GDALAllRegister();
  const io::Dem dem = io::read_dem(test::shared_data("st_helens_crater.tif"), {}, nullptr);
  par::MetaOptions o;
  o.elimination.importance = GENERATE(core::Importance::vp, core::Importance::pld);
  o.keep.percent = 10.0;
  par::MetaStats stats;
  const par::MetaResult r = par::simplify_meta(io::GdalRaster(dem), o, nullptr, &stats);
  CHECK(stats.pieces.size() == 16);
  CHECK(r.tin.cells.size() == 1638);
  test::check_tin(dem.grid, r.tin, dem.frame);
  const core::MeshCheck mc = core::check_mesh(dem.output_xy(r.tin.cells), r.tin.faces);
  CHECK(mc.area == Approx(127.0 * 30 * 127 * 30).epsilon(1e-12));
}

TEST_CASE("Andorra SRTM voids stay open with VP' on many small pieces", "[shared][meta]") {
  GDALAllRegister();
  const io::Dem dem = io::read_dem(test::shared_data("pyrenees_andorra_voids.tif"), {}, nullptr);
  par::MetaOptions o;
  o.keep.percent = 10.0;
  o.levels = 6;
  o.tile_bytes = 1 << 20;
  par::MetaStats stats;
  const par::MetaResult r = par::simplify_meta(io::GdalRaster(dem), o, nullptr, &stats);
  CHECK(stats.pieces.size() >= 64);
  CHECK(r.tin.cells.size() == 1566);  // round(0.1 x 15658), outline floors made up elsewhere
  CHECK(core::faces_over_nodata(dem.grid, test::grid_xy(dem.grid, r.tin), r.tin.faces) == 0);
  const core::MeshCheck mc = core::check_mesh(dem.output_xy(r.tin.cells), r.tin.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
  // In the frame (exact) the faces cover the footprint once.
  test::check_tin(dem.grid, r.tin, dem.frame);
}

TEST_CASE("Andorra SRTM voids stay open and the output is in UTM metres", "[shared][simplify]") {
  const Result r = simplify_file("pyrenees_andorra_voids.tif", core::Importance::vp, 10.0);
  CHECK(r.dem.output_crs_name.find("32631") != std::string::npos);
  CHECK(core::faces_over_nodata(r.dem.grid, test::grid_xy(r.dem.grid, r.tin), r.tin.faces) == 0);
  const auto xy = r.dem.output_xy(r.tin.cells);
  const core::MeshCheck mc = core::check_mesh(xy, r.tin.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
  // Metres, not degrees: cells of about 68 m (east-west at 42.7N) in UTM zone 31N.
  CHECK(r.dem.frame.metres_per_unit == Approx(68.1).epsilon(0.01));
  for (std::size_t i = 0; i < xy.size(); i += 2) {
    CHECK((xy[i] > 300000 && xy[i] < 400000 && xy[i + 1] > 4.70e6 && xy[i + 1] < 4.75e6));
  }
}

TEST_CASE("Kilauea's salt-and-pepper sea voids stay open", "[shared][simplify][.slow]") {
  const Result r = simplify_file("kilauea_utm5.tif", core::Importance::vp, 10.0);
  CHECK(core::faces_over_nodata(r.dem.grid, test::grid_xy(r.dem.grid, r.tin), r.tin.faces) == 0);
  const core::MeshCheck mc = core::check_mesh(r.dem.output_xy(r.tin.cells), r.tin.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
  CHECK(mc.area == Approx(core::footprint_area_cells(r.dem.grid) * 900.0).epsilon(1e-9));
}

#include "parallel/evaluate.hpp"
#include "support/exact_geodesic.hpp"

TEST_CASE("Steiner distances on real 50 x 50 crops: within 1 % of exact on average, never below",
          "[shared][geodesic][exact]") {
  struct Crop {
    const char* file;
    int c0, r0;
  };
  for (const Crop c :
       {Crop{"st_helens_crater.tif", 39, 39}, Crop{"san_gabriel_bigtujunga_utm11.tif", 600, 300}}) {
    INFO(c.file);
    const auto mesh = test::dem_crop(test::shared_data(c.file), c.c0, c.r0, 50);
    const double delta = par::kDefaultDeltaFactor * core::mean_edge_length(mesh);
    const auto fig = test::steiner_accuracy(mesh, delta, 4, 25, 7);
    CHECK(fig.min_rel > -1e-9);
    CHECK(fig.mean_rel < 0.01);
  }
}

TEST_CASE("Andorra SRTM voids: qem keeps the footprint, and the pinched outline whole",
          "[shared][qslim]") {
  GDALAllRegister();
  const io::Dem dem = io::read_dem(test::shared_data("pyrenees_andorra_voids.tif"), {}, nullptr);
  // The grid TIN in the frame, as dpts-par gives it to qem: voids touching at a corner pinch
  // the outline at a vertex there.
  const core::Tin tin = core::grid_tin(dem.grid, core::delaunay_diagonal(dem.frame));
  core::TriMesh in;
  for (std::uint32_t cell : tin.cells) {
    const int c = static_cast<int>(cell % static_cast<std::uint32_t>(dem.width));
    const int r = static_cast<int>(cell / static_cast<std::uint32_t>(dem.width));
    in.xyz.insert(in.xyz.end(), {dem.frame.u(c, r), dem.frame.w(c, r),
                                 dem.grid.z[cell] / dem.frame.metres_per_unit});
  }
  in.faces = tin.faces;
  core::fix_orientation(in);
  const core::TriMesh out = core::qem_simplify(in, in.vertex_count() / 10).mesh;
  CHECK(out.vertex_count() == in.vertex_count() / 10);
  const core::MeshCheck mc = core::check_mesh(core::xy_of(out.xyz), out.faces);
  CHECK(mc.clockwise_or_flat == 0);
  CHECK(mc.bad_edges == 0);
  CHECK(mc.area == Approx(core::mesh_area(core::xy_of(in.xyz), in.faces)).epsilon(1e-12));
  // Every vertex in some face, and no two at one place (a pinch split in two would be).
  std::vector<char> used(out.vertex_count(), 0);
  for (const auto& f : out.faces) {
    for (auto v : f) used[v] = 1;
  }
  CHECK(std::count(used.begin(), used.end(), 0) == 0);
  std::set<std::pair<double, double>> places;
  for (std::size_t v = 0; v < out.vertex_count(); ++v) {
    places.insert({out.xyz[3 * v], out.xyz[3 * v + 1]});
  }
  CHECK(places.size() == out.vertex_count());
}

#include "parallel/qem_engine.hpp"

TEST_CASE("Andorra SRTM voids: qem's pieces in UTM leave every void open, unfolded on the grid too",
          "[shared][qem]") {
  // In UTM the grid lines bend: three cells of one row make a sliver that is counter-clockwise
  // there but flat on the grid, across the void cell between them (1 face at 10 % before qem
  // refused folds on the grid as well).
  GDALAllRegister();
  const io::Dem dem = io::read_dem(test::shared_data("pyrenees_andorra_voids.tif"), {}, nullptr);
  for (const double percent : {10.0, 30.0}) {
    INFO(percent << " %");
    par::QemEngineOptions o;
    o.keep.percent = percent;
    o.levels = 2;
    par::MetaStats st;
    const core::TriMesh m = par::simplify_qem(io::GdalRaster(dem), o, nullptr, &st);
    CHECK(st.pieces.size() == 4);
    CHECK(m.vertex_count() == par::target_count(o.keep, st.input_vertices));
    const std::vector<double> xy = core::xy_of(m.xyz);
    const core::MeshCheck out = core::check_mesh(xy, m.faces);
    CHECK(out.clockwise_or_flat == 0);
    CHECK(out.bad_edges == 0);
    // On the grid (the inverse of the projection, as dpts-eval reads a mesh): no face flat or
    // folded, none over a void's centre (within the reprojection's rounding, 1 % of a cell).
    std::vector<double> grid = dem.grid_xy(xy);
    for (std::size_t i = 1; i < grid.size(); i += 2) grid[i] = -grid[i];  // rows run south
    CHECK(core::check_mesh(grid, m.faces).clockwise_or_flat == 0);
    for (std::size_t i = 1; i < grid.size(); i += 2) grid[i] = -grid[i];
    CHECK(core::faces_over_nodata(dem.grid, grid, m.faces, 0.01) == 0);
  }
}

TEST_CASE("peru_mongon at 50-95 % with qem: no face flat or folded in the output CRS",
          "[shared][qem]") {
  // An optimum nearly on the line of two corners made faces a rounding error from flat in the
  // frame, which the map to UTM turned flat or clockwise (2 at 70 %, 10 at 90 %): refused as
  // slivers now, so dpts-par writes what it made.
  GDALAllRegister();
  const io::Dem dem = io::read_dem(test::shared_data("peru_mongon.tif"), {}, nullptr);
  for (const double percent : {50.0, 70.0, 80.0, 90.0, 95.0}) {
    INFO(percent << " %");
    par::QemEngineOptions o;
    o.keep.percent = percent;
    par::MetaStats st;
    const core::TriMesh m = par::simplify_qem(io::GdalRaster(dem), o, nullptr, &st);
    CHECK(m.vertex_count() == par::target_count(o.keep, st.input_vertices));
    const core::MeshCheck mc = core::check_mesh(core::xy_of(m.xyz), m.faces);
    CHECK(mc.clockwise_or_flat == 0);
    CHECK(mc.bad_edges == 0);
  }
}

TEST_CASE("qem's pieces with --max-error: every valid cell centre within the bound",
          "[shared][qem]") {
  // Across 8 pieces and the merge (which reads the cells under its triangles again, block by
  // block), on a DEM in its own CRS and a reprojected one with voids; alone and with a count.
  GDALAllRegister();
  for (const char* name : {"st_helens_crater.tif", "pyrenees_andorra_voids.tif"}) {
    const io::Dem dem = io::read_dem(test::shared_data(name), {}, nullptr);
    const core::TriMesh full = dem.grid_mesh();
    for (const double bound : {2.0, 8.0}) {
      for (const std::size_t count : {std::size_t{3}, std::size_t{2000}}) {
        INFO(name << ", --max-error " << bound << ", " << count << " vertices");
        par::QemEngineOptions o;
        o.keep.vertices = count;
        o.levels = 3;
        o.max_error = bound;
        o.tile_bytes = 1 << 20;  // the merge's cache: 2 blocks of cells (at least 4 kept)
        par::MetaStats st;
        const core::TriMesh m = par::simplify_qem(io::GdalRaster(dem), o, nullptr, &st);
        CHECK(st.pieces.size() == 8);
        CHECK(m.vertex_count() >= count);
        CHECK(core::check_mesh(core::xy_of(m.xyz), m.faces).clockwise_or_flat == 0);
        const core::PointLocator locate(m);
        // Reprojected, the outline's chords may stray from the bent grid lines by 1 % of a
        // cell: cells on the outline are found as dpts-eval does, within half a cell.
        const double snap = dem.to_output ? 0.5 * dem.frame.metres_per_unit : 0.0;
        double worst = 0;
        std::size_t outside = 0;
        for (std::size_t v = 0; v < full.vertex_count(); ++v) {
          const auto hit = locate.locate(full.xyz[3 * v], full.xyz[3 * v + 1], snap);
          if (!hit) {
            ++outside;
            continue;
          }
          worst = std::max(worst, std::fabs(hit->point.z - full.xyz[3 * v + 2]));
        }
        CHECK(outside == 0);
        CHECK(worst <= bound);
        CHECK(worst > 0.5 * bound);  // the bound is what stops it (or the count, at 2000)
      }
    }
  }
}

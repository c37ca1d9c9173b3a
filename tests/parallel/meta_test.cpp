// The piece engine (PLD'/VP'): exact counts, an exact footprint across piece borders, the same
// result as the whole-DEM elimination for one piece, any thread count, piece values.
#include "parallel/meta.hpp"

#include <gdal_priv.h>
#include <tbb/global_control.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "core/footprint.hpp"
#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

struct Fixture {
  test::TempDir dir;
  std::string path = (dir / "hills.tif").string();
  core::HeightGrid grid;  // as stored (Float32)
  io::DemInfo info;
  Fixture() {
    GDALAllRegister();
    test::write_geotiff(path, test::hills_with_voids(), {500000, 30, 0, 4100000, 0, -30}, "");
    grid = io::read_dem(path, {}, nullptr).grid;
    info = io::open_dem(path, {});
  }
};

par::MetaOptions options(std::size_t keep, int levels, std::size_t tile_bytes) {
  par::MetaOptions o;
  o.keep.vertices = keep;
  o.levels = levels;
  o.tile_bytes = tile_bytes;
  o.value_points = 8;
  return o;
}

}  // namespace

TEST_CASE("VP' and PLD' keep exactly the requested count with an exact footprint across pieces",
          "[parallel][meta]") {
  Fixture fx;
  const std::size_t input = core::surface_cells(fx.grid).size();
  auto kind = GENERATE(core::Importance::vp, core::Importance::pld);
  for (double share : {0.3, 0.1}) {
    auto o = options(static_cast<std::size_t>(share * input), 4, 64 << 10);
    o.elimination.importance = kind;
    par::MetaStats stats;
    const par::MetaResult r = par::simplify_meta(io::GdalRaster(fx.info), o, nullptr, &stats);
    CHECK(stats.pieces.size() >= 16);
    CHECK(stats.input_vertices == input);
    CHECK(r.tin.cells.size() == o.keep.vertices.value());
    REQUIRE(r.z.size() == r.tin.cells.size());
    for (std::size_t i = 0; i < r.z.size(); ++i) CHECK(r.z[i] == fx.grid.z[r.tin.cells[i]]);
    // Delaunay, counter-clockwise, area = footprint area, nothing over a void.
    test::check_tin(fx.grid, r.tin, fx.info.frame);
    std::size_t budgets = 0;
    for (const auto& p : stats.pieces) budgets += p.budget;
    CHECK(budgets == o.keep.vertices.value());
  }
}

TEST_CASE("one piece gives exactly the whole-DEM elimination", "[parallel][meta]") {
  Fixture fx;
  const std::size_t input = core::surface_cells(fx.grid).size();
  auto o = options(input / 5, 0, std::size_t{1} << 40);
  par::MetaStats stats;
  const par::MetaResult r = par::simplify_meta(io::GdalRaster(fx.info), o, nullptr, &stats);
  REQUIRE(stats.pieces.size() == 1);
  const core::Tin whole = par::simplify_dem(fx.grid, fx.info.frame, o.elimination, o.keep, nullptr);
  CHECK(r.tin.cells == whole.cells);
  CHECK(r.tin.faces == whole.faces);
}

TEST_CASE("VP' gives the same TIN for 1, 2 and 4 threads", "[parallel][meta][determinism]") {
  Fixture fx;
  const std::size_t input = core::surface_cells(fx.grid).size();
  const auto o = options(input / 10, 4, 48 << 10);
  auto run = [&](int threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism,
                          static_cast<std::size_t>(threads));
    return par::simplify_meta(io::GdalRaster(fx.info), o, nullptr).tin;
  };
  const core::Tin a = run(1);
  for (int threads : {2, 4}) {
    const core::Tin b = run(threads);
    CHECK(a.cells == b.cells);
    CHECK(a.faces == b.faces);
  }
}

TEST_CASE("piece values: about 1 on a plane, lower on rough ground", "[parallel][meta]") {
  const core::GridFrame frame;  // 1 m cells
  const auto plane = test::make_grid(40, 40, [](int c, int r) { return 0.2 * c + 0.1 * r; });
  const auto rough = test::make_grid(
      40, 40, [](int c, int r) { return 3.0 * std::sin(c * 0.9) * std::cos(r * 0.7); });
  const double v_plane = par::piece_value(plane, 0, 0, frame, 12, 4096, 1);
  const double v_rough = par::piece_value(rough, 0, 0, frame, 12, 4096, 1);
  // Steiner paths are a little longer than straight lines even on a plane.
  CHECK(v_plane > 0.99);
  CHECK(v_plane <= 1.0);
  CHECK(v_rough < v_plane - 0.05);
  const auto voids = test::make_grid(3, 3, [](int, int) { return kNaN; });
  CHECK(par::piece_value(voids, 0, 0, frame, 12, 4096, 1) == 1.0);
}

TEST_CASE("piece values on a subsampled grid track the full-resolution values",
          "[parallel][meta]") {
  // Hills of several wavelengths (>= 12 cells) and heights: the cheaper value (at most 1024
  // cells, every 4th row and column of 128 x 128) stays close to the full one (16384 cells)
  // and orders the pieces the same way.
  core::GridFrame frame;
  frame.metres_per_unit = 10.0;
  std::vector<double> full, cheap;
  for (double height : {5.0, 20.0, 60.0}) {
    const auto g = test::make_grid(128, 128, [height](int c, int r) {
      return height * (std::sin(c * 0.13) * std::cos(r * 0.11) + 0.5 * std::sin((c + r) * 0.05));
    });
    full.push_back(par::piece_value(g, 0, 0, frame, 20, 1 << 30, 3));
    cheap.push_back(par::piece_value(g, 0, 0, frame, 20, 1024, 3));
  }
  for (std::size_t i = 0; i < full.size(); ++i) {
    INFO("height " << i << ": full " << full[i] << ", subsampled " << cheap[i]);
    CHECK(std::fabs(full[i] - cheap[i]) < 0.01);
  }
  CHECK(full[0] > full[1]);
  CHECK(full[1] > full[2]);
  CHECK(cheap[0] > cheap[1]);
  CHECK(cheap[1] > cheap[2]);
}

// Reading DEMs with GDAL: no-data, CRS handling, errors.
#include "io/dem_reader.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <limits>

#include "core/errors.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {
const double kNaN = std::numeric_limits<double>::quiet_NaN();
std::string epsg_wkt(int code) {
  OGRSpatialReference srs;
  srs.importFromEPSG(code);
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  std::string out = wkt;
  CPLFree(wkt);
  return out;
}
}  // namespace

TEST_CASE("a projected DEM is read with its no-data and exact metric frame", "[io][dem]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g =
      test::make_grid(6, 5, [](int c, int r) { return c == 2 && r == 3 ? kNaN : c * 10.0 + r; });
  test::write_geotiff(dir / "dem.tif", g, {500000, 30, 0, 4100000, 0, -30}, epsg_wkt(32611));
  const io::Dem dem = io::read_dem((dir / "dem.tif").string(), {}, nullptr);
  CHECK(dem.grid.width == 6);
  CHECK(dem.valid_cells == 29);
  CHECK(std::isnan(dem.grid.z[dem.grid.index(2, 3)]));
  CHECK(dem.grid.z[dem.grid.index(4, 1)] == 41.0);
  CHECK(dem.frame.metres_per_unit == 30.0);
  CHECK(dem.frame.m[1][1] == -1.0);
  CHECK(dem.output_wkt.find("UTM zone 11N") != std::string::npos);
  const auto xy = dem.output_xy({0, 7});
  CHECK(xy == std::vector<double>{500015, 4099985, 500045, 4099955});
}

TEST_CASE("a geographic DEM is projected to the UTM zone of its centre", "[io][dem]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(10, 10, [](int c, int r) { return c + r; });
  // 3 arc-second cells at 42.5N 1.5E: UTM 31N, cells about 68 m x 93 m.
  const double d = 1.0 / 1200;
  test::write_geotiff(dir / "geo.tif", g, {1.5, d, 0, 42.5, 0, -d}, epsg_wkt(4326));
  const io::Dem dem = io::read_dem((dir / "geo.tif").string(), {}, nullptr);
  CHECK(dem.output_crs_name.find("32631") != std::string::npos);
  REQUIRE_FALSE(dem.notes.empty());
  CHECK(dem.notes[0].find("projecting") != std::string::npos);
  CHECK(dem.frame.metres_per_unit == Approx(68.5).epsilon(0.01));  // 92.6 m x cos(42.5)
  CHECK(dem.frame.m[1][1] * dem.frame.metres_per_unit == Approx(-92.6).epsilon(0.01));
  const auto xy = dem.output_xy({0});
  CHECK(xy[0] == Approx(377000).margin(3000));  // 1.5 degrees west of 3E at 42.5N: ~123 km
}

TEST_CASE("the output CRS asked for must be a projected CRS GDAL knows", "[io][dem]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(4, 4, [](int c, int r) { return c + r; });
  test::write_geotiff(dir / "dem.tif", g, {500000, 30, 0, 4100000, 0, -30}, epsg_wkt(32611));
  CHECK_THROWS_AS(io::read_dem((dir / "dem.tif").string(), {"EPSG:4326"}, nullptr), UsageError);
  CHECK_THROWS_AS(io::read_dem((dir / "dem.tif").string(), {"nonsense"}, nullptr), UsageError);
  const io::Dem dem = io::read_dem((dir / "dem.tif").string(), {"EPSG:32610"}, nullptr);
  CHECK(dem.output_crs_name.find("32610") != std::string::npos);
}

TEST_CASE("a DEM without CRS is read as metres with a warning", "[io][dem]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(4, 4, [](int c, int r) { return c + r; });
  test::write_geotiff(dir / "nocrs.tif", g, {0, 2, 0, 0, 0, -2}, "");
  const io::Dem dem = io::read_dem((dir / "nocrs.tif").string(), {}, nullptr);
  CHECK(dem.output_wkt.empty());
  REQUIRE(dem.notes.size() == 1);
  CHECK(dem.notes[0].find("no CRS") != std::string::npos);
  CHECK(dem.frame.metres_per_unit == 2.0);
}

TEST_CASE("bad rasters are refused naming the file", "[io][dem]") {
  GDALAllRegister();
  test::TempDir dir;
  CHECK_THROWS_WITH(io::read_dem((dir / "missing.tif").string(), {}, nullptr),
                    Catch::Contains("missing.tif") && Catch::Contains("no such file"));
  std::ofstream(dir / "text.tif") << "not a raster\n";
  CHECK_THROWS_WITH(io::read_dem((dir / "text.tif").string(), {}, nullptr),
                    Catch::Contains("text.tif") && Catch::Contains("not a raster"));
  const auto g = test::make_grid(4, 4, [](int, int) { return kNaN; });
  test::write_geotiff(dir / "void.tif", g, {0, 1, 0, 0, 0, -1}, "");
  CHECK_THROWS_WITH(io::read_dem((dir / "void.tif").string(), {}, nullptr),
                    Catch::Contains("void.tif") && Catch::Contains("all no-data"));
}

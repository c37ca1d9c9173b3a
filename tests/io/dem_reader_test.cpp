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
using test::epsg_wkt;
double zat(const core::HeightGrid& g, int c, int r) {
  return g.z[static_cast<std::size_t>(r) * g.width + c];
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
  CHECK(dem.notes[0].find("degrees") == std::string::npos);
  CHECK(dem.frame.metres_per_unit == 2.0);
  // Cells of 3 arc-seconds at 42 N, 1.5 E, without their CRS: maybe degrees, said.
  const double arc = 1.0 / 1200;
  test::write_geotiff(dir / "lonlat.tif", g, {1.5, arc, 0, 42.0, 0, -arc}, "");
  const io::Dem lonlat = io::read_dem((dir / "lonlat.tif").string(), {}, nullptr);
  REQUIRE(lonlat.notes.size() == 1);
  CHECK(lonlat.notes[0].find("if they are degrees, give it its CRS") != std::string::npos);
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

TEST_CASE("every real cell type is read exactly, with scale, offset and signed bytes", "[io][dem]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(6, 5, [](int c, int r) { return 10.0 * r + c; });
  for (const char* type : {"Byte", "UInt16", "Int16", "UInt32", "Int32", "UInt64", "Int64",
                           "Float32", "Float64"}) {
    INFO(type);
    test::RasterSpec spec;
    spec.type = type;
    spec.has_nodata = true;
    spec.nodata = 12;  // the cell (2, 1) becomes no-data
    test::write_raster(dir / "t.tif", g, spec);
    const io::Dem dem = io::read_dem((dir / "t.tif").string(), {}, nullptr);
    CHECK(dem.type_name == type);
    CHECK(std::isnan(zat(dem.grid, 2, 1)));
    CHECK(dem.valid_cells == 29);
    CHECK(zat(dem.grid, 5, 4) == 45.0);
    CHECK(zat(dem.grid, 0, 0) == 0.0);
  }
  // Int8 as GDAL 3.6 stores it: Byte marked PIXELTYPE=SIGNEDBYTE.
  test::RasterSpec sbyte;
  sbyte.type = "Byte";
  sbyte.creation_options = {"PIXELTYPE=SIGNEDBYTE"};
  test::write_raster(dir / "s.tif", test::make_grid(3, 3, [](int c, int r) { return -100.0 + 3 * r + c; }),
                     sbyte);
  const io::Dem s = io::read_dem((dir / "s.tif").string(), {}, nullptr);
  CHECK(s.signed_byte);
  CHECK(zat(s.grid, 0, 0) == -100.0);
  CHECK(zat(s.grid, 2, 2) == -92.0);
  // Heights stored in centimetres: value x 0.01 + 100.
  test::RasterSpec scaled;
  scaled.type = "Int32";
  scaled.scale = 0.01;
  scaled.offset = 100;
  test::write_raster(dir / "cm.tif", test::make_grid(3, 3, [](int c, int r) { return 250.0 * (r * 3 + c); }),
                     scaled);
  const io::Dem cm = io::read_dem((dir / "cm.tif").string(), {}, nullptr);
  CHECK(zat(cm.grid, 1, 0) == Approx(102.5).epsilon(1e-12));
  CHECK(zat(cm.grid, 2, 2) == Approx(120.0).epsilon(1e-12));
  REQUIRE_FALSE(cm.notes.empty());
  CHECK(cm.notes.back().find("heights = stored value x 0.01 + 100") != std::string::npos);
}

TEST_CASE("another band, absurd and non-finite heights", "[io][dem]") {
  GDALAllRegister();
  test::TempDir dir;
  test::RasterSpec two;
  two.bands = 2;  // band 2 = band 1 + 1000
  const auto g = test::make_grid(4, 4, [](int c, int r) {
    if (c == 1 && r == 1) return std::numeric_limits<double>::infinity();
    if (c == 2 && r == 1) return -3.4e38;  // an undeclared Float32 no-data
    if (c == 3 && r == 1) return kNaN;
    return double(c + r);
  });
  test::write_raster(dir / "b.tif", g, two);
  io::DemReadOptions second;
  second.band = 2;
  const io::Dem dem = io::read_dem((dir / "b.tif").string(), second, nullptr);
  CHECK(dem.band == 2);
  CHECK(zat(dem.grid, 0, 0) == 1000.0);
  CHECK(std::isnan(zat(dem.grid, 1, 1)));
  CHECK(std::isnan(zat(dem.grid, 2, 1)));
  CHECK(std::isnan(zat(dem.grid, 3, 1)));
  CHECK(dem.valid_cells == 13);
  const io::Dem first = io::read_dem((dir / "b.tif").string(), {}, nullptr);
  REQUIRE(first.notes.size() == 3);  // two bands, no CRS, absurd heights
  CHECK(first.notes[0].find("2 bands; using band 1") != std::string::npos);
  // note: the infinite and the -3.4e38 cell; NaN is a no-data of its own, not told.
  CHECK(first.notes[2].find("2 cells with heights beyond +-1e7 read as no-data") !=
        std::string::npos);
}

TEST_CASE("usual no-data values in a band without one are heights, and said", "[io][dem]") {
  // A void that lost its tag reads as a pit 9999 m deep: kept (the band says it is a height),
  // counted per value, and the note names the commonest and how to tag it.
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(6, 5, [](int c, int r) {
    if (r == 2 && c < 3) return -9999.0;
    if (r == 4 && c == 5) return -32768.0;
    return 100.0 + c + r;
  });
  test::write_raster(dir / "untagged.tif", g, {});
  const io::Dem dem = io::read_dem((dir / "untagged.tif").string(), {}, nullptr);
  CHECK(dem.valid_cells == 30);
  CHECK(zat(dem.grid, 1, 2) == -9999.0);
  REQUIRE_FALSE(dem.notes.empty());
  CHECK(dem.notes.back() == "warning: " + (dir / "untagged.tif").string() +
                                ": 3 cells hold -9999 (1 more hold another), a usual no-data "
                                "value, but band 1 has none: read as heights; if they are voids, "
                                "give the band its no-data value (gdal_translate -a_nodata -9999 "
                                "IN OUT)");
  // Tagged, the same cells are no-data and nothing is said of them: only of the -32768 one.
  test::RasterSpec tagged;
  tagged.has_nodata = true;
  tagged.nodata = -9999;
  test::write_raster(dir / "tagged.tif", g, tagged);
  const io::Dem t = io::read_dem((dir / "tagged.tif").string(), {}, nullptr);
  CHECK(t.valid_cells == 27);
  REQUIRE(t.height_warnings.size() == 1);
  CHECK(t.height_warnings[0].find(": 1 cells hold -32768, a usual no-data value, but band 1's "
                                  "no-data value is -9999") != std::string::npos);
  // Tagged with another value, the cells not holding it are heights, and said.
  test::RasterSpec other;
  other.has_nodata = true;
  other.nodata = -32768;
  test::write_raster(dir / "other.tif", g, other);
  const io::Dem o = io::read_dem((dir / "other.tif").string(), {}, nullptr);
  CHECK(o.valid_cells == 29);
  REQUIRE_FALSE(o.notes.empty());
  CHECK(o.notes.back() == "warning: " + (dir / "other.tif").string() +
                              ": 3 cells hold -9999, a usual no-data value, but band 1's no-data "
                              "value is -32768: read as heights; if they are voids, set them to "
                              "-32768");
  // Heights near but not at those values say nothing.
  const auto deep = test::make_grid(6, 5, [](int c, int r) { return -9998.5 - c - r; });
  test::write_raster(dir / "deep.tif", deep, {});
  for (const auto& note : io::read_dem((dir / "deep.tif").string(), {}, nullptr).notes)
    CHECK(note.find("usual no-data") == std::string::npos);
}

TEST_CASE("a DEM replaced or rewritten after it was opened fails the next window read",
          "[io][dem][robust]") {
  // The piece engines read windows through handles of their own: a file replaced mid-run
  // would otherwise mix two DEMs in one TIN.
  GDALAllRegister();
  test::TempDir dir;
  const auto path = (dir / "dem.tif").string(), other = (dir / "other.tif").string();
  auto grid = [](double base) {
    return test::make_grid(12, 10, [base](int c, int r) { return base + c + 2.0 * r; });
  };
  const double gt[6] = {400000, 10, 0, 3800000, 0, -10};
  test::write_geotiff(path, grid(100), {gt[0], gt[1], gt[2], gt[3], gt[4], gt[5]}, epsg_wkt(32611));
  for (const bool rename : {true, false}) {
    INFO((rename ? "replaced by a rename" : "rewritten in place"));
    const io::DemInfo dem = io::open_dem(path, {});
    CHECK(io::WindowReader(dem).read(0, 0, 12, 10).z[0] == (rename ? 100.0 : 500.0));
    if (rename) {
      test::write_geotiff(other, grid(500), {gt[0], gt[1], gt[2], gt[3], gt[4], gt[5]},
                          epsg_wkt(32611));
      std::filesystem::rename(other, path);
    } else {
      std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(0, std::ios::end);
      f << "x";  // grows: another size (and time)
    }
    io::WindowReader reader(dem);
    CHECK_THROWS_WITH(reader.read(0, 0, 12, 10),
                      path +
                          ": changed while it was being read (replaced or rewritten); no "
                          "output written");
  }
}

TEST_CASE("longitudes 0-360 get the UTM zone of their meridian", "[io][dem][robust]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(10, 10, [](int c, int r) { return c + r; });
  // 200.5E = 159.5W at 20N (Hawaii): UTM zone 4N, not 60 (the zone clamped from 200.5).
  const double d = 1.0 / 1200;
  test::write_geotiff(dir / "geo.tif", g, {200.5, d, 0, 20.0, 0, -d}, epsg_wkt(4326));
  const io::Dem dem = io::read_dem((dir / "geo.tif").string(), {}, nullptr);
  CHECK(dem.output_crs_name.find("32604") != std::string::npos);
  const auto xy = dem.output_xy({0});
  CHECK(xy[0] == Approx(448000).margin(3000));  // 0.5 degrees west of 159W at 20N: ~52 km
}

TEST_CASE("a geocentric CRS is refused, and heights in feet, km or cm become metres", "[io][dem][robust]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(10, 10, [](int c, int r) { return 100.0 + c + r; });
  const auto tif = (dir / "dem.tif").string();
  test::write_geotiff(tif, g, {400000, 10, 0, 3800000, 0, -10}, epsg_wkt(32611));
  // The same cells labelled with the geocentric WGS 84 (EPSG:4978), through a VRT.
  std::ofstream(dir / "ecef.vrt")
      << "<VRTDataset rasterXSize=\"10\" rasterYSize=\"10\"><SRS>EPSG:4978</SRS><GeoTransform>"
         "400000, 10, 0, 3800000, 0, -10</GeoTransform><VRTRasterBand dataType=\"Float32\" "
         "band=\"1\"><SimpleSource><SourceFilename relativeToVRT=\"1\">dem.tif</SourceFilename>"
         "<SourceBand>1</SourceBand></SimpleSource></VRTRasterBand></VRTDataset>\n";
  const auto ecef = (dir / "ecef.vrt").string();
  CHECK_THROWS_WITH(io::open_dem(ecef, {}), Catch::StartsWith(ecef + ": has a geocentric CRS ("));
  // Heights in feet (the band's unit type).
  std::ofstream(dir / "feet.vrt")
      << "<VRTDataset rasterXSize=\"10\" rasterYSize=\"10\"><GeoTransform>400000, 10, 0, "
         "3800000, 0, -10</GeoTransform><VRTRasterBand dataType=\"Float32\" band=\"1\">"
         "<UnitType>ft</UnitType><SimpleSource><SourceFilename relativeToVRT=\"1\">dem.tif"
         "</SourceFilename><SourceBand>1</SourceBand></SimpleSource></VRTRasterBand>"
         "</VRTDataset>\n";
  const auto feet = (dir / "feet.vrt").string();
  const io::Dem dem = io::read_dem(feet, {}, nullptr);
  CHECK(dem.grid.z[0] == Approx(100.0 * 0.3048).epsilon(1e-12));
  CHECK(dem.grid.z[11] == Approx(102.0 * 0.3048).epsilon(1e-12));
  bool said = false;
  for (const auto& n : dem.notes) said = said || n.find("heights in ft") != std::string::npos;
  CHECK(said);
  // Other units: km and cm converted, "metres above sea level" metres, one not known said.
  auto with_unit = [&](const std::string& name, const std::string& unit) {
    std::ofstream(dir / name) << "<VRTDataset rasterXSize=\"10\" rasterYSize=\"10\"><GeoTransform>"
                                 "400000, 10, 0, 3800000, 0, -10</GeoTransform><VRTRasterBand "
                                 "dataType=\"Float32\" band=\"1\"><UnitType>"
                              << unit
                              << "</UnitType><SimpleSource><SourceFilename relativeToVRT=\"1\">"
                                 "dem.tif</SourceFilename><SourceBand>1</SourceBand></SimpleSource>"
                                 "</VRTRasterBand></VRTDataset>\n";
    return io::read_dem((dir / name).string(), {}, nullptr);
  };
  auto warned = [](const io::Dem& d) {
    bool w = false;
    for (const auto& n : d.notes) w = w || n.find("a unit dpts does not know") != std::string::npos;
    return w;
  };
  const io::Dem km = with_unit("km.vrt", "km");
  CHECK(km.grid.z[0] == Approx(100000.0).epsilon(1e-12));
  CHECK(with_unit("cm.vrt", "cm").grid.z[0] == Approx(1.0).epsilon(1e-12));
  const io::Dem asl = with_unit("asl.vrt", "metres above sea level");
  CHECK(asl.grid.z[0] == 100.0);
  CHECK_FALSE(warned(asl));
  const io::Dem odd = with_unit("odd.vrt", "furlong");
  CHECK(odd.grid.z[0] == 100.0);
  CHECK(warned(odd));
}

TEST_CASE("cells masked out by a mask or alpha band are no-data", "[io][dem][robust]") {
  GDALAllRegister();
  test::TempDir dir;
  const auto g = test::make_grid(12, 10, [](int c, int r) { return 100.0 + c + r; });
  // The masked-out cells: columns 3-5 of rows 2-4.
  auto masked = [](int c, int r) { return c >= 3 && c <= 5 && r >= 2 && r <= 4; };
  std::vector<GByte> mask(12 * 10);
  for (int r = 0; r < 10; ++r) {
    for (int c = 0; c < 12; ++c) mask[r * 12 + c] = masked(c, r) ? 0 : 255;
  }
  const auto with_mask = (dir / "mask.tif").string();
  test::write_geotiff(with_mask, g, {400000, 10, 0, 3800000, 0, -10}, epsg_wkt(32611));
  {
    std::unique_ptr<GDALDataset> ds(GDALDataset::Open(with_mask.c_str(), GDAL_OF_UPDATE));
    REQUIRE(ds);
    REQUIRE(ds->CreateMaskBand(GMF_PER_DATASET) == CE_None);
    REQUIRE(ds->GetRasterBand(1)->GetMaskBand()->RasterIO(GF_Write, 0, 0, 12, 10, mask.data(), 12,
                                                          10, GDT_Byte, 0, 0, nullptr) == CE_None);
  }
  // Heights in band 1, an alpha band 2 (GDAL takes alpha as the mask for Byte and UInt16).
  const auto alpha_tif = (dir / "alpha.tif").string();
  {
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    std::unique_ptr<GDALDataset> ds(
        gtiff->Create(alpha_tif.c_str(), 12, 10, 2, GDT_UInt16, nullptr));
    REQUIRE(ds);
    double gt[6] = {400000, 10, 0, 3800000, 0, -10};
    ds->SetGeoTransform(gt);
    std::vector<std::uint16_t> z(g.z.begin(), g.z.end()), a(mask.begin(), mask.end());
    REQUIRE(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 12, 10, z.data(), 12, 10, GDT_UInt16, 0,
                                           0, nullptr) == CE_None);
    REQUIRE(ds->GetRasterBand(2)->RasterIO(GF_Write, 0, 0, 12, 10, a.data(), 12, 10, GDT_UInt16, 0,
                                           0, nullptr) == CE_None);
    ds->GetRasterBand(2)->SetColorInterpretation(GCI_AlphaBand);
  }
  for (const auto& path : {with_mask, alpha_tif}) {
    INFO(path);
    const io::Dem dem = io::read_dem(path, {}, nullptr);
    for (int r = 0; r < 10; ++r) {
      for (int c = 0; c < 12; ++c) CHECK(dem.grid.is_valid(c, r) == !masked(c, r));
    }
    CHECK(dem.valid_cells == 120 - 9);
  }
}

TEST_CASE("a subdataset name with a driver prefix opens", "[io][dem][robust]") {
  // GTIFF_DIR:1:f.tif (the first image of a GeoTIFF) was refused as "no such file".
  GDALAllRegister();
  test::TempDir dir;
  const auto path = (dir / "dem.tif").string();
  test::write_geotiff(path, test::make_grid(12, 10, [](int c, int r) { return 1.0 * c + r; }),
                      {400000, 10, 0, 3800000, 0, -10}, epsg_wkt(32611));
  const io::Dem dem = io::read_dem("GTIFF_DIR:1:" + path, {}, nullptr);
  CHECK(dem.width == 12);
  CHECK(dem.grid.z[13] == 2.0);
  CHECK_THROWS_WITH(io::open_dem("GTIFF_DIR:1:" + (dir / "none.tif").string(), {}),
                    Catch::StartsWith("GTIFF_DIR:1:" + (dir / "none.tif").string() +
                                      ": not a raster GDAL can read"));
}

// dpts-eval as users run it: figures, JSON, exit codes.
#include <gdal_priv.h>
#include <sys/stat.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh_check.hpp"
#include "io/json.hpp"
#include "io/ply.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {
const std::string kPar = DPTS_PAR_EXE;
const std::string kEval = DPTS_EVAL_EXE;

struct Fixture {
  test::TempDir dir;
  std::string dem = (dir / "dem.tif").string();
  Fixture() {
    const auto g = test::make_grid(24, 18, [](int c, int r) {
      if (c > 8 && c < 11 && r > 6 && r < 9) return std::numeric_limits<double>::quiet_NaN();
      return 300.0 + 25.0 * std::sin(c * 0.5) * std::cos(r * 0.4);
    });
    test::write_geotiff(dem, g, {400000, 10, 0, 3800000, 0, -10}, "");
  }
};

std::string last_line(const std::string& s) {
  const auto end = s.find_last_not_of('\n');
  const auto start = s.rfind('\n', end);
  return s.substr(start == std::string::npos ? 0 : start + 1,
                  end - (start == std::string::npos ? 0 : start + 1) + 1);
}
}  // namespace

TEST_CASE("a geographic DEM with longitudes past 180 is simplified and measured as in -180..180",
          "[cli][eval][crs]") {
  // The same hills at lon -1.025 and at 358.975 (0..360), and across 180 (179.975 to 180.025,
  // against 179.925 to 179.975): points mapped back from UTM get PROJ's -180..180 longitudes,
  // which must be brought to the DEM's own range (they landed 360 degrees off the grid: qem's
  // grid plane wrong, every face "over no-data").
  test::TempDir dir;
  const auto g = test::make_grid(60, 60, [](int c, int r) {
    return 400.0 + 80.0 * std::sin(c * 0.21) * std::cos(r * 0.17) + 2.0 * c;
  });
  const double cell = 0.0008333;
  auto figures = [&](const std::string& name, double lon0) {
    const auto dem = (dir / (name + ".tif")).string(), mesh = (dir / (name + ".ply")).string();
    test::write_geotiff(dem, g, {lon0, cell, 0, 10.0, 0, -cell}, test::epsg_wkt(4326));
    REQUIRE(test::run(kPar, {"--quiet", dem, mesh}).exit_code == 0);
    const auto r = test::run(kEval, {"--json", "--quiet", "--dem", dem, "--mesh", mesh, "--points",
                                     "12", "--sets", "1"});
    INFO(name << ": " << r.err);
    REQUIRE(r.exit_code == 0);
    const std::string js = last_line(r.out);
    CHECK(io::json_field(js, "faces_over_nodata") == "0");
    return std::pair{std::stod(io::json_field(js, "vertical_rmse").value_or("nan")),
                     std::stod(io::json_field(js, "mesh_vertices").value_or("nan"))};
  };
  const auto west = figures("west", -1.025), wrapped = figures("wrapped", 358.975);
  CHECK(wrapped.second == west.second);
  CHECK(wrapped.first == Approx(west.first).epsilon(0.01));
  const auto before = figures("before", 179.925), across = figures("across", 179.975);
  CHECK(across.second == before.second);
  CHECK(across.first == Approx(before.first).epsilon(0.05));
}

TEST_CASE("a mesh in a CRS of feet is measured in metres, as in the DEM's own metres",
          "[cli][eval][crs]") {
  // Hills near Mount St Helens in UTM 10N (metres), simplified and measured there and in
  // Washington South State Plane (US survey feet): the output's heights stay metres, so
  // dpts-eval scales the mesh's x, y to metres (in feet the relief was flattened 3.28 x and
  // the error came out 5 to 7 x too low).
  test::TempDir dir;
  const auto dem = (dir / "dem.tif").string();
  const auto g = test::make_grid(50, 50, [](int c, int r) {
    return 1500.0 + 120.0 * std::sin(c * 0.25) * std::cos(r * 0.2) + 4.0 * r;
  });
  test::write_geotiff(dem, g, {560000, 20, 0, 5120000, 0, -20}, test::epsg_wkt(32610));
  auto error = [&](const std::vector<std::string>& crs) {
    const auto mesh = (dir / (crs.empty() ? "m.ply" : "ft.ply")).string();
    std::vector<std::string> par{"--quiet", "--keep", "10%"};
    par.insert(par.end(), crs.begin(), crs.end());
    par.insert(par.end(), {dem, mesh});
    REQUIRE(test::run(kPar, par).exit_code == 0);
    std::vector<std::string> eval{"--json", "--quiet",  "--dem", dem,      "--mesh",
                                  mesh,     "--points", "12",    "--sets", "1"};
    eval.insert(eval.end(), crs.begin(), crs.end());
    const auto r = test::run(kEval, eval);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    return std::stod(io::json_field(last_line(r.out), "distance_error").value_or("nan"));
  };
  const double metres = error({}), feet = error({"--t-srs", "EPSG:2927"});
  CHECK(metres > 0);
  CHECK(feet == Approx(metres).epsilon(0.25));
}

TEST_CASE("dpts-eval measures the band dpts-par simplified (--band), and names the one it reads",
          "[cli][eval]") {
  // Band 2 lies 500 m above band 1: measured against band 1 the mesh of band 2 is 500 m off.
  test::TempDir dir;
  const auto dem = (dir / "two.tif").string(), mesh = (dir / "m.ply").string();
  const auto band1 = test::make_grid(
      30, 20, [](int c, int r) { return 300.0 + 25.0 * std::sin(c * 0.5) * std::cos(r * 0.4); });
  const auto band2 = test::make_grid(
      30, 20, [](int c, int r) { return 800.0 + 25.0 * std::sin(c * 0.5) * std::cos(r * 0.4); });
  test::RasterSpec two;
  two.bands = 2;
  two.geotransform = {400000, 10, 0, 3800000, 0, -10};
  two.wkt = test::epsg_wkt(32611);
  test::write_raster(dem, band1, two);
  {
    GDALAllRegister();
    std::unique_ptr<GDALDataset> ds(
        GDALDataset::Open(dem.c_str(), GDAL_OF_UPDATE | GDAL_OF_RASTER));
    REQUIRE(ds);
    std::vector<float> z(band2.z.begin(), band2.z.end());
    REQUIRE(ds->GetRasterBand(2)->RasterIO(GF_Write, 0, 0, 30, 20, z.data(), 30, 20, GDT_Float32, 0,
                                           0) == CE_None);
  }
  REQUIRE(test::run(kPar, {"--quiet", "--band", "2", dem, mesh}).exit_code == 0);
  auto rmse = [&](const std::vector<std::string>& band, std::string* err = nullptr) {
    std::vector<std::string> args{"--json",   "--dem", dem,      "--mesh", mesh,
                                  "--points", "6",     "--sets", "1"};
    args.insert(args.end(), band.begin(), band.end());
    const auto r = test::run(kEval, args);
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    if (err) *err = r.err;
    return std::stod(io::json_field(last_line(r.out), "vertical_rmse").value_or("nan"));
  };
  std::string err;
  CHECK(rmse({"--band", "2"}) < 5.0);
  CHECK(rmse({}, &err) == Approx(500.0).epsilon(0.02));
  CHECK(err.rfind("dpts-eval: " + dem + ": 2 bands; using band 1 (--band picks another)\n", 0) ==
        0);
  const auto none = test::run(kEval, {"--dem", dem, "--mesh", mesh, "--band", "3"});
  CHECK(none.exit_code == 1);
  CHECK(none.err == "dpts-eval: error: " + dem + ": has 2 bands; there is no band 3\n");
  // The note waits for the measure: a failure before it is one line alone.
  const std::string missing = (dir / "missing.ply").string();
  const auto no_mesh = test::run(kEval, {"--dem", dem, "--mesh", missing});
  CHECK(no_mesh.exit_code == 1);
  CHECK(no_mesh.err == "dpts-eval: error: " + missing + ": no such file\n");
}

TEST_CASE("dpts-eval says the DEM's warnings: voids that lost their no-data tag", "[cli][eval]") {
  // A -9999 void without a no-data tag is a pit 9999 m deep in T: the measure is of the pit,
  // and the user is told, as dpts-par tells its own.
  test::TempDir dir;
  const auto dem = (dir / "untagged.tif").string(), mesh = (dir / "m.ply").string();
  test::RasterSpec spec;
  spec.geotransform = {400000, 10, 0, 3800000, 0, -10};
  spec.wkt = test::epsg_wkt(32611);
  test::write_raster(dem, test::make_grid(30, 20, [](int c, int r) {
                       return c == 4 && r == 4 ? -9999.0 : 300.0 + 2.0 * c + r;
                     }), spec);
  const std::string warning = "warning: " + dem + ": 1 cells hold -9999, a usual no-data value";
  const auto par = test::run(kPar, {dem, mesh});
  REQUIRE(par.exit_code == 0);
  CHECK(par.err.find("dpts-par: " + warning) != std::string::npos);
  const auto r = test::run(kEval, {"--dem", dem, "--mesh", mesh, "--points", "6", "--sets", "1"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.find("dpts-eval: " + warning) != std::string::npos);
  // --quiet says nothing; --json holds the warning.
  const auto j = test::run(kEval, {"--quiet", "--json", "--dem", dem, "--mesh", mesh, "--points",
                                   "6", "--sets", "1"});
  CHECK(j.err.empty());
  const std::string warnings = io::json_field(last_line(j.out), "warnings").value_or("");
  CHECK(warnings.rfind("[\"" + warning, 0) == 0);
}

TEST_CASE("dpts-eval reports every figure in one JSON line", "[cli][eval]") {
  Fixture fx;
  const auto mesh = (fx.dir / "m.ply").string();
  REQUIRE(test::run(kPar, {"--quiet", "--keep", "30%", fx.dem, mesh}).exit_code == 0);
  const auto r = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--points", "20", "--json"});
  REQUIRE(r.exit_code == 0);
  const std::string js = last_line(r.out);
  CHECK(js.front() == '{');
  CHECK(js.back() == '}');
  for (const char* key : {"\"distance_error\":", "\"distance_error_sets\":[",
                          "\"vertical_rmse\":", "\"vertical_max\":", "\"mesh_vertices\":",
                          "\"mesh_faces\":", "\"dem_vertices\":", "\"points\":20",
                          "\"seconds\":", "\"faces_over_nodata\":0", "\"faces_not_ccw\":0"}) {
    INFO(key);
    CHECK(js.find(key) != std::string::npos);
  }
  // The footprint covered exactly, up to the rounding of the area sums.
  const auto at = js.find("\"coverage\":");
  REQUIRE(at != std::string::npos);
  CHECK(std::stod(js.substr(at + 11)) == Approx(1.0).epsilon(1e-12));
  CHECK(r.out.find(
            "validity         0 faces not counter-clockwise, 0 bad edges, 0 faces over no-data") !=
        std::string::npos);
}

TEST_CASE("dpts-eval refuses bad usage with exit 2 and bad meshes with exit 1", "[cli][eval]") {
  Fixture fx;
  CHECK(test::run(kEval, {"--dem", fx.dem}).exit_code == 2);
  const auto bad = test::run(kEval, {"--dem", fx.dem, "--mesh", "x.ply", "--points", "1"});
  CHECK(bad.exit_code == 2);
  CHECK(bad.err.rfind("dpts-eval: --points 1: expected an integer >= 2", 0) == 0);
  std::ofstream(fx.dir / "junk.ply") << "ply\nformat ascii 1.0\nelement vertex 1\n";
  const auto junk = test::run(kEval, {"--dem", fx.dem, "--mesh", (fx.dir / "junk.ply").string()});
  CHECK(junk.exit_code == 1);
  CHECK(junk.err.find("junk.ply") != std::string::npos);
}

TEST_CASE("dpts-eval keeps to --max-memory or refuses in one line", "[cli][eval][memory]") {
  Fixture fx;
  const auto mesh = (fx.dir / "m.ply").string();
  REQUIRE(test::run(kPar, {"--quiet", "--keep", "30%", fx.dem, mesh}).exit_code == 0);
  const std::vector<std::string> base = {"--dem",    fx.dem, "--mesh",  mesh,
                                         "--points", "20",   "--quiet", "--json"};
  auto with = [&](std::vector<std::string> extra) {
    extra.insert(extra.begin(), base.begin(), base.end());
    return test::run(kEval, extra);
  };
  const auto zero = with({"--max-memory", "0"});
  CHECK(zero.exit_code == 2);
  CHECK(zero.err.rfind("dpts-eval: --max-memory 0: expected an integer >= 1 (MB)", 0) == 0);
  // Less than the DEM and meshes already hold.
  const auto tiny = with({"--max-memory", "1"});
  CHECK(tiny.exit_code == 1);
  CHECK(tiny.out.empty());
  CHECK(tiny.err.rfind("dpts-eval: error: --max-memory 1: the run holds ", 0) == 0);
  CHECK(std::count(tiny.err.begin(), tiny.err.end(), '\n') == 1);
  // Room for the run but not for its Steiner graphs: a delta of 0.1 mm makes them huge.
  const auto fine = with({"--max-memory", "200", "--delta", "0.0001"});
  CHECK(fine.exit_code == 1);
  CHECK(fine.err.rfind("dpts-eval: error: the geodesics need about ", 0) == 0);
  CHECK(fine.err.find("available (--max-memory); use a larger --delta or fewer --points\n") !=
        std::string::npos);
  // Enough: the same figures as with no limit given.
  const auto ok = with({"--max-memory", "2000"});
  const auto free_run = with({});
  REQUIRE(ok.exit_code == 0);
  REQUIRE(free_run.exit_code == 0);
  auto error_of = [](const std::string& js) {
    const auto at = js.find("\"distance_error\":");
    return js.substr(at, js.find(',', at) - at);
  };
  CHECK(error_of(ok.out) == error_of(free_run.out));
}

TEST_CASE("dpts-eval answers each malformed mesh clearly", "[cli][eval][robust]") {
  Fixture fx;
  // A valid mesh of the DEM to start from: 3 x 3 vertices at cell centres, 8 faces.
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
      "property double y\nproperty double z\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  const std::string square =
      "400005 3799995 300\n400235 3799995 300\n400235 3799825 300\n"
      "400005 3799825 300\n";
  struct Case {
    std::string what, text;
    int exit_code;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"truncated", head + square + "3 0 2 1\n3 0", 1, "truncated PLY data"},
      {"fewer vertices than the header says", head + "400005 3799995 300\n3 0 2 1\n", 1,
       "truncated PLY data"},
      {"face index out of range", head + square + "3 0 2 1\n3 0 3 7\n", 1,
       "face 1 has vertex index out of range"},
      {"a quad", head + square + "4 0 3 2 1\n3 0 2 1\n", 1, "face 0 is not a triangle"},
      {"NaN coordinate",
       head + "nan 3799995 300\n" + square.substr(square.find('\n') + 1) + "3 0 2 1\n3 0 3 2\n", 1,
       "vertex 0 has a non-finite coordinate"},
      {"face repeating a vertex", head + square + "3 0 2 1\n3 0 0 2\n", 1,
       "face 1 repeats a vertex"},
      {"negative list length", head + square + "3 0 2 1\n-3 0 3 2\n", 1, "bad PLY list length"},
      {"vertices outside the DEM", head + "0 0 300\n1 0 300\n1 1 300\n0 1 300\n3 0 1 2\n3 0 2 3\n",
       1, "vertex 0 (0.000000, 0.000000) lies outside"},
      {"no faces",
       "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
       "property double z\nend_header\n400005 3799995 300\n",
       1, "has no faces"},
      // Documented treatment: folded and flat faces are measured and reported, not refused.
      {"a folded face", head + square + "3 0 2 1\n3 0 2 3\n", 0, ""},
      {"a flat face",
       "ply\nformat ascii 1.0\nelement vertex 5\nproperty double x\nproperty double y\n"
       "property double z\nelement face 3\nproperty list uchar int vertex_indices\nend_header\n" +
           square + "400120 3799995 300\n3 0 2 1\n3 0 3 2\n3 0 4 1\n",
       0, ""},
  };
  for (const auto& c : cases) {
    INFO(c.what);
    const auto mesh = (fx.dir / "m.ply").string();
    std::ofstream(mesh, std::ios::trunc) << c.text;
    const auto r = test::run(kEval, {"--json", "--quiet", "--dem", fx.dem, "--mesh", mesh});
    CHECK(r.exit_code == c.exit_code);
    if (c.exit_code != 0) {
      CHECK(r.err.rfind("dpts-eval: error: " + mesh + ": " + c.message, 0) == 0);
      CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    } else {
      CHECK(r.out.find("\"faces_not_ccw\":1") != std::string::npos);
    }
  }
}

namespace {

// Writes a sample-point file of the fixture DEM: S sets of K <= 6 points inside T, west of its
// no-data hole (one exactly on the west outline edge).
std::string sample_file(const test::TempDir& dir, int sets, int k) {
  const auto path = (dir / "pts.csv").string();
  std::ofstream out(path);
  out.precision(17);
  out << "set,x,y\n";
  for (int s = 0; s < sets; ++s) {
    for (int i = 0; i < k; ++i) {
      const double x = i == 0 ? 400005.0 : 400012.5 + 12.1 * i + 3.3 * s;
      const double y = 3799990.0 - 11.7 * i - 23.9 * s;
      out << s << "," << x << "," << y << "\n";
    }
  }
  return path;
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out(1);
  for (char ch : line) {
    if (ch == sep) {
      out.emplace_back();
    } else {
      out.back() += ch;
    }
  }
  return out;
}

// The mesh file of a dpts-par run on the fixture DEM (30 % kept).
std::string simplified_mesh(const Fixture& fx) {
  const auto mesh = (fx.dir / "m.ply").string();
  REQUIRE(test::run(kPar, {"--quiet", "--keep", "30%", fx.dem, mesh}).exit_code == 0);
  return mesh;
}

}  // namespace

TEST_CASE("dpts-eval measures the pairs of --sample-points and writes each with --pairs-out",
          "[cli][eval][sample]") {
  Fixture fx;
  const auto mesh = simplified_mesh(fx);
  const auto pts = sample_file(fx.dir, 3, 6);
  const auto pairs = (fx.dir / "pairs.csv").string();
  const auto r = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--sample-points", pts,
                                   "--pairs-out", pairs, "--json"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const std::string js = last_line(r.out);
  CHECK(io::json_field(js, "points") == "6");
  CHECK(io::json_field(js, "sets") == "3");
  CHECK(io::json_field(js, "pairs_measured") == "45");
  CHECK(io::json_field(js, "pairs_unconnected_dem") == "0");
  CHECK(io::json_field(js, "sample_points") == pts);
  CHECK(r.out.find("distance error   sample set 0: ") != std::string::npos);
  CHECK(r.out.find("pairs            45 measured; left out: 0 not connected on T, 0 at "
                   "distance 0") != std::string::npos);
  // Every pair i < j of every set, rel_err = |gd_T - gd_S| / gd_T; their mean is the set's error.
  std::ifstream in(pairs);
  std::string line;
  std::getline(in, line);
  CHECK(line == "set,i,j,gd_T,gd_S,rel_err");
  std::vector<double> sum(3, 0.0);
  std::size_t rows = 0;
  while (std::getline(in, line)) {
    const auto f = split(line, ',');
    REQUIRE(f.size() == 6);
    const double gd_t = std::stod(f[3]), gd_s = std::stod(f[4]), rel = std::stod(f[5]);
    CHECK(std::stoi(f[1]) < std::stoi(f[2]));
    CHECK(rel == std::fabs(gd_t - gd_s) / gd_t);
    sum[std::stoul(f[0])] += rel;
    ++rows;
  }
  CHECK(rows == 3 * 6 * 5 / 2);
  const auto sets = split(io::json_field(js, "distance_error_sets").value_or("[]"), ',');
  REQUIRE(sets.size() == 3);
  CHECK(std::stod(sets[1]) == Approx(sum[1] / 15).epsilon(1e-12));
}

TEST_CASE("dpts-eval refuses --sample-points with --points or --sets, and outputs over inputs",
          "[cli][eval][sample]") {
  Fixture fx;
  const auto pts = sample_file(fx.dir, 1, 3);
  for (const char* flag : {"--points", "--sets"}) {
    const auto r =
        test::run(kEval, {"--dem", fx.dem, "--mesh", "m.ply", "--sample-points", pts, flag, "5"});
    CHECK(r.exit_code == 2);
    CHECK(
        r.err.rfind(
            "dpts-eval: --sample-points and " + std::string(flag) +
                " cannot be combined (the file gives the points and sets); see dpts-eval --help\n",
            0) == 0);
  }
  const auto exact =
      test::run(kEval, {"--dem", fx.dem, "--mesh", "m.ply", "--exact", "--delta", "3"});
  CHECK(exact.exit_code == 2);
  CHECK(exact.err.rfind("dpts-eval: --exact and --delta cannot be combined", 0) == 0);
  const auto over = test::run(
      kEval, {"--dem", fx.dem, "--mesh", "m.ply", "--sample-points", pts, "--pairs-out", pts});
  CHECK(over.exit_code == 2);
  CHECK(over.err.rfind(
            "dpts-eval: --pairs-out " + pts + ": is an input of the run; see dpts-eval --help\n",
            0) == 0);
}

TEST_CASE("dpts-eval draws the error map and the hillshades, only when the run succeeds",
          "[cli][eval][pictures]") {
  Fixture fx;
  const auto mesh = simplified_mesh(fx);
  const auto map = (fx.dir / "error.png").string(), shade = (fx.dir / "shade.png").string();
  const auto r =
      test::run(kEval, {"--quiet", "--dem", fx.dem, "--mesh", mesh, "--points", "4", "--sets", "1",
                        "--error-map", map, "--hillshade-compare", shade, "--edges"});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(test::file_bytes(map).rfind("\x89PNG\r\n\x1a\n", 0) == 0);
  CHECK(test::file_bytes(shade).rfind("\x89PNG\r\n\x1a\n", 0) == 0);

  // A run that fails (a point outside the mesh) leaves neither; nor does bad usage.
  std::filesystem::remove(map);
  std::filesystem::remove(shade);
  const auto pts = (fx.dir / "far.csv").string();
  std::ofstream(pts) << "set,x,y\n0,400020,3799980\n0,500000,3700000\n";
  const auto failed =
      test::run(kEval, {"--quiet", "--dem", fx.dem, "--mesh", mesh, "--sample-points", pts,
                        "--error-map", map, "--hillshade-compare", shade});
  CHECK(failed.exit_code == 1);
  CHECK_FALSE(std::filesystem::exists(map));
  CHECK_FALSE(std::filesystem::exists(shade));
  const auto edges = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--edges"});
  CHECK(edges.exit_code == 2);
  CHECK(edges.err.rfind("dpts-eval: --edges: needs --hillshade-compare; see dpts-eval --help\n",
                        0) == 0);
  const auto over = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--error-map", mesh});
  CHECK(over.exit_code == 2);
  CHECK(over.err.rfind(
            "dpts-eval: --error-map " + mesh + ": is an input of the run; see dpts-eval --help\n",
            0) == 0);
  // Two outputs in one file: refused (the later would replace the earlier), not written.
  const auto twice = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--error-map", map,
                                       "--pairs-out", (fx.dir / "." / "error.png").string()});
  CHECK(twice.exit_code == 2);
  CHECK(twice.err.rfind(
            "dpts-eval: --pairs-out and --error-map: the same file; see dpts-eval --help\n", 0) ==
        0);
  CHECK_FALSE(std::filesystem::exists(map));
  const auto nowhere = test::run(
      kEval, {"--dem", fx.dem, "--mesh", mesh, "--hillshade-compare", "/nonexistent/s.png"});
  CHECK(nowhere.exit_code == 1);
  CHECK(nowhere.err.find("/nonexistent/s.png") != std::string::npos);
}

TEST_CASE("dpts-eval reads flags as dpts-par does: --flag=value, and -- ends the flags",
          "[cli][eval]") {
  Fixture fx;
  const auto mesh = simplified_mesh(fx);
  const auto r = test::run(
      kEval, {"--quiet", "--json", "--points=4", "--sets=1", "--dem=" + fx.dem, "--mesh", mesh});
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(io::json_field(last_line(r.out), "points") == "4");
  CHECK(io::json_field(last_line(r.out), "sets") == "1");
  const auto after = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--", "--points"});
  CHECK(after.exit_code == 2);
  CHECK(after.err.rfind("dpts-eval: --points: unexpected argument; see dpts-eval --help\n", 0) ==
        0);
  const auto missing = test::run(kEval, {"--dem", fx.dem, "--mesh"});
  CHECK(missing.exit_code == 2);
  CHECK(missing.err.rfind("dpts-eval: --mesh: missing value; see dpts-eval --help\n", 0) == 0);
}

TEST_CASE("dpts-eval refuses --points whose pair tables cannot fit, before any work",
          "[cli][eval][robust]") {
  Fixture fx;
  // 10^6 points: 5 x 10^11 pairs a set (a bare std::bad_alloc before; 30000 were killed by
  // the kernel's OOM killer).
  const auto r = test::run(kEval, {"--dem", fx.dem, "--mesh", "m.ply", "--points", "1000000"});
  CHECK(r.exit_code == 1);
  CHECK(r.err.rfind("dpts-eval: error: --points 1000000: the 1000000 x 1000000 pairs of 3 sets "
                    "need about ",
                    0) == 0);
  CHECK(r.err.find(" available\n") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  // Within the memory available but not within --max-memory: the same arrays, the same count
  // the geodesics' plan makes (3000 points: about 2.0 GB for 3 sets), refused before the DEM
  // is read (the mesh is not even looked at).
  const auto capped = test::run(
      kEval, {"--dem", fx.dem, "--mesh", "m.ply", "--points", "3000", "--max-memory", "400"});
  CHECK(capped.exit_code == 1);
  CHECK(capped.err.rfind("dpts-eval: error: --points 3000: the 3000 x 3000 pairs of 3 sets need "
                         "about 1.9 GB, more than the 400 MB available (--max-memory)\n",
                         0) == 0);
  const auto one_set = test::run(kEval, {"--dem", fx.dem, "--mesh", "m.ply", "--points", "3000",
                                         "--sets", "1", "--max-memory", "400"});
  CHECK(one_set.exit_code == 1);
  CHECK(one_set.err.find("pairs of 1 set need about ") != std::string::npos);
}

TEST_CASE("dpts-eval refuses a --pairs-out that is a file of the DEM's dataset",
          "[cli][eval][robust]") {
  test::TempDir dir;
  test::RasterSpec envi;
  envi.driver = "ENVI";
  envi.geotransform = {400000, 10, 0, 3800000, 0, -10};
  envi.wkt = test::epsg_wkt(32611);
  const std::string dem = (dir / "dem.envi").string(), hdr = (dir / "dem.hdr").string();
  test::write_raster(dem, test::make_grid(12, 10, [](int c, int r) { return 100.0 + c + r; }),
                     envi);
  const std::string before = test::file_bytes(hdr);
  const auto r = test::run(kEval, {"--dem", dem, "--mesh", "m.ply", "--pairs-out", hdr});
  CHECK(r.exit_code == 2);
  CHECK(r.err.rfind("dpts-eval: --pairs-out " + hdr + ": is " + hdr +
                        ", a file of the DEM; see dpts-eval --help\n",
                    0) == 0);
  CHECK(test::file_bytes(hdr) == before);
}

TEST_CASE("dpts-eval answers each bad sample-point file in one line and writes nothing",
          "[cli][eval][sample][robust]") {
  Fixture fx;
  const auto mesh = simplified_mesh(fx);
  struct Case {
    std::string what, text, message;
  };
  const std::vector<Case> cases = {
      {"bad header", "set;x;y\n0;1;2\n", "line 1: expected the header set,x,y, found 'set;x;y'"},
      {"wrong column count", "set,x,y\n0,400020,3799980\n0,400030\n",
       "line 3: expected 3 values set,x,y, found 2"},
      {"a value not a number", "set,x,y\n0,400020,3799980\n0,400030,north\n",
       "line 3: y 'north': expected a finite number"},
      {"sets not contiguous",
       "set,x,y\n0,400020,3799980\n0,400030,3799970\n2,400020,3799980\n"
       "2,400030,3799970\n",
       "line 4: set 2, but set 1 has no points (sets are numbered from 0 without gaps)"},
      {"a set of one point", "set,x,y\n0,400020,3799980\n", "line 2: set 0 has only this point"},
  };
  const auto pts = (fx.dir / "bad.csv").string();
  const auto pairs = (fx.dir / "pairs.csv").string();
  for (const auto& c : cases) {
    INFO(c.what);
    std::ofstream(pts, std::ios::trunc) << c.text;
    const auto r = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--sample-points", pts,
                                     "--pairs-out", pairs, "--json"});
    CHECK(r.exit_code == 1);
    CHECK(r.out.empty());
    CHECK(r.err.rfind("dpts-eval: error: " + pts + ": " + c.message, 0) == 0);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK(fx.dir.files() == std::vector<std::string>{"bad.csv", "dem.tif", "m.ply"});
  }
  // A point outside the DEM's footprint (west of it by a metre), with the count.
  std::ofstream(pts, std::ios::trunc) << "set,x,y\n0,400020,3799980\n0,400004,3799900\n"
                                         "0,400030,3799970\n";
  const auto outside = test::run(
      kEval, {"--dem", fx.dem, "--mesh", mesh, "--sample-points", pts, "--pairs-out", pairs});
  CHECK(outside.exit_code == 1);
  CHECK(outside.err ==
        "dpts-eval: error: 1 of 3 points of sample set 0 lie outside the DEM's footprint\n");
  CHECK(fx.dir.files() == std::vector<std::string>{"bad.csv", "dem.tif", "m.ply"});
}

TEST_CASE("dpts-eval fails in one line when an output cannot be written, leaving no file",
          "[cli][eval][robust]") {
  Fixture fx;
  const auto mesh = simplified_mesh(fx);
  const std::vector<std::string> base = {"--dem",    fx.dem, "--mesh", mesh,
                                         "--points", "8",    "--sets", "1"};
  auto with = [&](std::vector<std::string> extra, const test::RunOptions& ro = {}) {
    extra.insert(extra.begin(), base.begin(), base.end());
    return test::run(kEval, extra, ro);
  };
  const std::vector<std::string> inputs = {"dem.tif", "m.ply"};
  // A folder that does not exist.
  const auto missing = (fx.dir / "no" / "pairs.csv").string();
  const auto r1 = with({"--pairs-out", missing});
  CHECK(r1.exit_code == 1);
  CHECK(r1.err == "dpts-eval: error: " + missing +
                      ": cannot create output (No such file or "
                      "directory)\n");
  CHECK(fx.dir.files() == inputs);
  // A full disk, for the pairs and for the report on stdout (text or JSON).
  const auto r2 = with({"--pairs-out", "/dev/full"});
  CHECK(r2.exit_code == 1);
  CHECK(r2.err == "dpts-eval: error: /dev/full: write failed (No space left on device)\n");
  const auto pairs = (fx.dir / "pairs.csv").string();
  test::RunOptions full;
  full.stdout_to = "/dev/full";
  for (const char* quiet : {"--json", "--quiet"}) {
    INFO(quiet);
    const auto r3 = with({"--json", quiet, "--pairs-out", pairs}, full);
    CHECK(r3.exit_code == 1);
    CHECK(r3.err == "dpts-eval: error: standard output: write failed (No space left on device)\n");
    CHECK(fx.dir.files() == inputs);
  }
  const auto text = with({"--pairs-out", pairs}, full);
  CHECK(text.exit_code == 1);
  CHECK(text.err == "dpts-eval: error: standard output: write failed (No space left on device)\n");
  CHECK(fx.dir.files() == inputs);
  // A file size limit (a full quota) hit while writing the pairs (nothing on stdout).
  test::RunOptions limit;
  limit.file_size_limit = 300;
  const auto r4 = with({"--quiet", "--pairs-out", pairs}, limit);
  CHECK(r4.exit_code == 1);
  CHECK(r4.err.rfind("dpts-eval: error: " + pairs + ": write failed", 0) == 0);
  CHECK(std::count(r4.err.begin(), r4.err.end(), '\n') == 1);
  CHECK(fx.dir.files() == inputs);
}

TEST_CASE("dpts-eval --exact measures with exact geodesics on a small DEM", "[cli][eval][exact]") {
  Fixture fx;
  const auto mesh = simplified_mesh(fx);
  const auto r = test::run(kEval, {"--dem", fx.dem, "--mesh", mesh, "--exact", "--points", "6",
                                   "--sets", "2", "--json"});
  REQUIRE(r.exit_code == 0);
  const std::string js = last_line(r.out);
  CHECK(io::json_field(js, "geodesics") == "exact");
  CHECK(io::json_field(js, "pairs_measured") == "30");
  CHECK(std::stod(io::json_field(js, "distance_error").value_or("0")) > 0);
  CHECK(r.out.find("geodesics        exact (CGAL Surface_mesh_shortest_path): T ") !=
        std::string::npos);
  // CGAL takes no folded face (measured without --exact): refused in one line naming it.
  const auto folded = (fx.dir / "folded.ply").string();
  std::ofstream(folded) << "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
                           "property double y\nproperty double z\nelement face 2\n"
                           "property list uchar int vertex_indices\nend_header\n"
                           "400005 3799995 300\n400235 3799995 300\n400235 3799825 300\n"
                           "400005 3799825 300\n3 0 2 1\n3 0 2 3\n";
  const auto bad =
      test::run(kEval, {"--dem", fx.dem, "--mesh", folded, "--exact", "--points", "4"});
  CHECK(bad.exit_code == 1);
  CHECK(bad.err.rfind("dpts-eval: error: " + folded +
                          ": face 1 cannot join the surface for "
                          "exact geodesics",
                      0) == 0);
  CHECK(std::count(bad.err.begin(), bad.err.end(), '\n') == 1);
}

TEST_CASE("dpts-eval fails with the count of pairs a mesh in two parts does not connect",
          "[cli][eval][robust]") {
  Fixture fx;
  // The DEM's own grid TIN less its column of squares from x = 400145 to 400155 m: two parts.
  const auto full = (fx.dir / "full.ply").string();
  REQUIRE(test::run(kPar, {"--quiet", "--keep", "100%", fx.dem, full}).exit_code == 0);
  io::Mesh m = io::read_ply_file(full);
  const std::size_t faces = m.faces.size();
  m.faces.erase(std::remove_if(m.faces.begin(), m.faces.end(),
                               [&](const std::array<std::uint32_t, 3>& f) {
                                 const double cx =
                                     (m.xyz[3 * f[0]] + m.xyz[3 * f[1]] + m.xyz[3 * f[2]]) / 3;
                                 return cx > 400145 && cx < 400155;
                               }),
                m.faces.end());
  REQUIRE(m.faces.size() == faces - 2 * 17);
  const auto slit = (fx.dir / "slit.ply").string();
  {
    std::ofstream out(slit, std::ios::binary);
    io::write_ply(out, m, io::PlyFormat::binary_little_endian);
  }
  const auto pts = (fx.dir / "pts.csv").string();
  std::ofstream(pts) << "set,x,y\n0,400020,3799980\n0,400100,3799900\n0,400200,3799950\n"
                        "0,400230,3799830\n";
  const auto r = test::run(kEval, {"--dem", fx.dem, "--mesh", slit, "--sample-points", pts});
  CHECK(r.exit_code == 1);
  CHECK(r.err ==
        "dpts-eval: error: the mesh does not connect 4 of the 6 pairs of sample set 0 "
        "that T connects (is it in several parts, or slit?)\n");
}

TEST_CASE("dpts-eval reports a seam left open inside the mesh by its boundary's length",
          "[cli][eval][robust]") {
  Fixture fx;
  // The DEM's own grid TIN, its faces right of x = 400155 m given their own copies of the
  // four vertices there between y = 3799895 and 3799945, 1 mm higher (identical ones would be
  // welded): a slit of 50 m, whose two sides cover the same area and still connect round it.
  const auto full = (fx.dir / "full.ply").string();
  REQUIRE(test::run(kPar, {"--quiet", "--keep", "100%", fx.dem, full}).exit_code == 0);
  io::Mesh m = io::read_ply_file(full);
  const double outline = core::check_mesh(core::xy_of(m.xyz), m.faces).boundary_length;
  const std::size_t n = m.vertex_count();
  std::vector<std::uint32_t> copy(n, 0);
  for (std::uint32_t v = 0; v < n; ++v) {
    const double x = m.xyz[3 * v], y = m.xyz[3 * v + 1];
    if (x == 400155 && y > 3799895 && y < 3799945) {
      copy[v] = static_cast<std::uint32_t>(m.vertex_count());
      m.xyz.insert(m.xyz.end(), {x, y, m.xyz[3 * v + 2] + 1e-3});  // not welded
    }
  }
  REQUIRE(m.vertex_count() == n + 4);
  for (auto& f : m.faces) {
    const double cx = (m.xyz[3 * f[0]] + m.xyz[3 * f[1]] + m.xyz[3 * f[2]]) / 3;
    if (cx <= 400155) continue;
    for (auto& v : f) v = copy[v] ? copy[v] : v;
  }
  const auto slit = (fx.dir / "slit.ply").string();
  {
    std::ofstream out(slit, std::ios::binary);
    io::write_ply(out, m, io::PlyFormat::binary_little_endian);
  }
  const std::vector<std::string> args = {"--dem", fx.dem, "--points", "12", "--sets", "1",
                                         "--json"};
  auto run_on = [&](const std::string& mesh) {
    std::vector<std::string> a = args;
    a.insert(a.end(), {"--mesh", mesh});
    return test::run(kEval, a);
  };
  const auto a = run_on(full), b = run_on(slit);
  REQUIRE(a.exit_code == 0);
  REQUIRE(b.exit_code == 0);
  auto ratio = [&](const test::RunResult& r) {
    return std::stod(io::json_field(last_line(r.out), "boundary_ratio").value_or("nan"));
  };
  CHECK(ratio(a) == Approx(1.0).epsilon(1e-12));
  CHECK(ratio(b) == Approx((outline + 100) / outline).epsilon(1e-9));
  CHECK(std::stod(io::json_field(last_line(b.out), "coverage").value_or("nan")) ==
        Approx(1.0).epsilon(1e-12));
  CHECK(io::json_field(last_line(b.out), "bad_edges") == "0");
  CHECK(a.out.find("a crack or slit inside") == std::string::npos);
  CHECK(b.out.find("(longer: a crack or slit inside, or a moved outline)") != std::string::npos);
}

TEST_CASE("dpts-eval welds a triangle soup and measures it as the indexed mesh",
          "[cli][eval][robust]") {
  Fixture fx;
  const auto mesh = simplified_mesh(fx);
  const io::Mesh indexed = io::read_ply_file(mesh);
  io::Mesh soup;
  for (const auto& f : indexed.faces) {
    const auto first = static_cast<std::uint32_t>(soup.vertex_count());
    for (auto v : f) {
      soup.xyz.insert(soup.xyz.end(), indexed.xyz.begin() + 3 * v, indexed.xyz.begin() + 3 * v + 3);
    }
    soup.faces.push_back({first, first + 1, first + 2});
  }
  const auto soup_path = (fx.dir / "soup.ply").string();
  {
    std::ofstream out(soup_path, std::ios::binary);
    io::write_ply(out, soup, io::PlyFormat::ascii);
  }
  const std::vector<std::string> common = {"--dem",  fx.dem, "--points", "12",
                                           "--sets", "2",    "--json"};
  auto run_on = [&](const std::string& m) {
    std::vector<std::string> args = common;
    args.insert(args.end(), {"--mesh", m});
    return test::run(kEval, args);
  };
  const auto a = run_on(mesh), b = run_on(soup_path);
  REQUIRE(a.exit_code == 0);
  REQUIRE(b.exit_code == 0);
  const std::string ja = last_line(a.out), jb = last_line(b.out);
  CHECK(io::json_field(ja, "merged_vertices") == "0");
  const std::size_t merged = soup.vertex_count() - indexed.vertex_count();
  CHECK(io::json_field(jb, "merged_vertices") == std::to_string(merged));
  CHECK(io::json_field(jb, "mesh_vertices") == std::to_string(indexed.vertex_count()));
  CHECK(io::json_field(jb, "bad_edges") == "0");
  CHECK(std::stod(io::json_field(jb, "distance_error").value_or("-1")) ==
        Approx(std::stod(io::json_field(ja, "distance_error").value_or("-2"))).epsilon(1e-12));
  CHECK(b.out.find("welded           " + std::to_string(merged) + " vertices") !=
        std::string::npos);
}

TEST_CASE("dpts-eval reads the mesh as OBJ, STL and GeoPackage and measures it as the PLY",
          "[cli][eval][formats]") {
  Fixture fx;
  const auto ply = simplified_mesh(fx);
  const std::vector<std::string> common = {"--dem",  fx.dem, "--points", "12",
                                           "--sets", "2",    "--json",   "--quiet"};
  auto measure = [&](const std::string& m) {
    std::vector<std::string> args = common;
    args.insert(args.end(), {"--mesh", m});
    return test::run(kEval, args);
  };
  const auto base = measure(ply);
  REQUIRE(base.exit_code == 0);
  const std::string jb = last_line(base.out);
  const std::vector<std::vector<std::string>> outputs = {
      {"m.obj"}, {"m.stl", "--ascii"}, {"m.gpkg"}, {"m_bin.stl"}};
  for (const auto& o : outputs) {
    INFO(o[0]);
    const auto path = (fx.dir / o[0]).string();
    std::vector<std::string> args = {"--quiet", "--keep", "30%", fx.dem, path};
    args.insert(args.end(), o.begin() + 1, o.end());
    REQUIRE(test::run(kPar, args).exit_code == 0);
    const auto r = measure(path);
    REQUIRE(r.exit_code == 0);
    const std::string j = last_line(r.out);
    CHECK(io::json_field(j, "mesh_vertices") == io::json_field(jb, "mesh_vertices"));
    CHECK(io::json_field(j, "mesh_faces") == io::json_field(jb, "mesh_faces"));
    CHECK(io::json_field(j, "bad_edges") == "0");
    const double e = std::stod(io::json_field(j, "distance_error").value_or("-1"));
    const double e0 = std::stod(io::json_field(jb, "distance_error").value_or("-2"));
    // note: binary STL holds float32: at these northings (3.8e6 m) corners move by up to
    // 0.125 m on 10 m cells, which moves the figure by about 1 %.
    CHECK(e == Approx(e0).epsilon(o[0] == "m_bin.stl" ? 0.05 : 1e-12));
  }
}

TEST_CASE("dpts-eval answers each malformed OBJ, STL and GeoPackage in one line",
          "[cli][eval][formats][robust]") {
  Fixture fx;
  const std::string v =
      "v 400005 3799995 300\nv 400235 3799995 300\nv 400235 3799825 300\n"
      "v 400005 3799825 300\n";
  struct Case {
    std::string name, text, message;
  };
  const std::vector<Case> cases = {
      {"quad.obj", v + "f 1 4 3 2\n", "line 5: a face of 4 corners; expected triangles"},
      {"index.obj", v + "f 1 2 9\n", "line 5: face corner 9: no such vertex"},
      {"word.obj", v + "f 1 2 x\n", "line 5: face corner x: expected a vertex number"},
      {"short.obj", "v 400005 3799995\n", "line 1: expected a vertex's x y z"},
      {"nofaces.obj", v, "has no faces"},
      {"two.stl",
       "solid t\nfacet normal 0 0 1\nouter loop\nvertex 400005 3799995 300\n"
       "vertex 400235 3799995 300\nendloop\nendfacet\nendsolid t\n",
       "ASCII STL, facet 0: expected three vertices"},
      {"open.stl", "solid t\nfacet normal 0 0 1\nouter loop\nvertex 400005 3799995 300\n",
       "ASCII STL, facet 0: the file ends inside it"},
      {"junk.stl", "not an stl at all\n",
       "neither binary STL (84 + 50 bytes per facet) nor ASCII STL"},
      {"junk.gpkg", "not a geopackage\n", "cannot open as a vector dataset"},
  };
  // A mesh that is not a file: refused at once, not read (a FIFO would block).
  {
    const auto dir = (fx.dir / "d.obj").string();
    std::filesystem::create_directory(dir);
    const auto fifo = (fx.dir / "f.ply").string();
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    const auto missing = (fx.dir / "missing.stl").string();
    for (const auto& [path, message] :
         {std::pair<std::string, std::string>{dir, "is a directory, not a mesh"},
          {fifo, "is a pipe or a device, not a mesh file"},
          {missing, "no such file"}}) {
      const auto r = test::run(kEval, {"--quiet", "--dem", fx.dem, "--mesh", path});
      CHECK(r.exit_code == 1);
      CHECK(r.err == "dpts-eval: error: " + path + ": " + message + "\n");
    }
    // The same for --sample-points (with a mesh that is fine).
    const auto mesh = simplified_mesh(fx);
    for (const auto& [path, message] :
         {std::pair<std::string, std::string>{dir, "is a directory, not a sample-point table"},
          {fifo, "is a pipe or a device, not a sample-point table file"}}) {
      const auto r =
          test::run(kEval, {"--quiet", "--dem", fx.dem, "--mesh", mesh, "--sample-points", path});
      CHECK(r.exit_code == 1);
      CHECK(r.err == "dpts-eval: error: " + path + ": " + message + "\n");
    }
  }
  for (const auto& c : cases) {
    INFO(c.name);
    const auto mesh = (fx.dir / c.name).string();
    std::ofstream(mesh, std::ios::trunc) << c.text;
    const auto r = test::run(kEval, {"--quiet", "--dem", fx.dem, "--mesh", mesh});
    CHECK(r.exit_code == 1);
    CHECK(r.err == "dpts-eval: error: " + mesh + ": " + c.message + "\n");
  }
}

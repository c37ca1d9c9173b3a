// dpts-eval as users run it: figures, JSON, exit codes.
#include <catch2/catch.hpp>
#include <cmath>
#include <algorithm>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

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
                          "\"mesh_faces\":", "\"dem_vertices\":", "\"points\":20", "\"seconds\":",
                          "\"faces_over_nodata\":0", "\"faces_not_ccw\":0", "\"coverage\":1,"}) {
    INFO(key);
    CHECK(js.find(key) != std::string::npos);
  }
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
  CHECK(fine.err.find("available (--max-memory); use a larger --delta\n") != std::string::npos);
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
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
                           "property double y\nproperty double z\nelement face 2\n"
                           "property list uchar int vertex_indices\nend_header\n";
  const std::string square = "400005 3799995 300\n400235 3799995 300\n400235 3799825 300\n"
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
      {"NaN coordinate", head + "nan 3799995 300\n" + square.substr(square.find('\n') + 1) +
                             "3 0 2 1\n3 0 3 2\n",
       1, "vertex 0 has a non-finite coordinate"},
      {"face repeating a vertex", head + square + "3 0 2 1\n3 0 0 2\n", 1,
       "face 1 repeats a vertex"},
      {"negative list length", head + square + "3 0 2 1\n-3 0 3 2\n", 1, "bad PLY list length"},
      {"vertices outside the DEM", head + "0 0 300\n1 0 300\n1 1 300\n0 1 300\n3 0 1 2\n3 0 2 3\n",
       1, "vertex 0 (0.000000, 0.000000) lies outside"},
      {"no faces", "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\nproperty double y\n"
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

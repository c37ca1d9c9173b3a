// dpts-eval as users run it: figures, JSON, exit codes.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <limits>

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

// dpts-mpi (built where Open MPI is found): on 1, 2 and 3 ranks the same bytes as dpts-par, and
// one line from rank 0 when it fails.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <limits>

#include "test_support.hpp"

#ifdef DPTS_MPI_EXE

using namespace dpts;

namespace {

// mpirun with n ranks of dpts-mpi (as root too; more ranks than cores).
test::RunResult mpirun(int n, const std::vector<std::string>& args,
                       const test::RunOptions& options = {}) {
  setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
  setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
  // note: -q: mpirun adds no banner of its own to a rank's failure.
  std::vector<std::string> all = {"-q", "-np", std::to_string(n), "--oversubscribe", DPTS_MPI_EXE};
  all.insert(all.end(), args.begin(), args.end());
  return test::run(DPTS_MPIEXEC, all, options);
}

std::string hills(const test::TempDir& dir) {
  const auto path = (dir / "dem.tif").string();
  test::write_geotiff(
      path,
      test::make_grid(160, 120,
                      [](int c, int r) {
                        if (c > 60 && c < 70 && r > 40 && r < 52) {
                          return std::numeric_limits<double>::quiet_NaN();
                        }
                        return 500.0 + 40.0 * std::sin(c * 0.11) * std::cos(r * 0.07) + 0.2 * r;
                      }),
      {400000, 10, 0, 3800000, 0, -10}, test::epsg_wkt(32611));
  return path;
}

}  // namespace

TEST_CASE("dpts-mpi on 1, 2 and 3 ranks writes the bytes dpts-par writes", "[cli][mpi]") {
  test::TempDir dir;
  const std::string dem = hills(dir);
  const auto expected_path = (dir / "par.ply").string();
  // --tile-mb 1 and 5 levels: 32 pieces or more to share out.
  const std::vector<std::string> common = {"--quiet", "--levels", "5", "--tile-mb", "1"};
  auto with = [&](std::vector<std::string> extra, const std::string& out) {
    std::vector<std::string> a = common;
    a.insert(a.end(), extra.begin(), extra.end());
    a.push_back(dem);
    a.push_back(out);
    return a;
  };
  REQUIRE(test::run(DPTS_PAR_EXE, with({"--threads", "2"}, expected_path)).exit_code == 0);
  const std::string expected = test::file_bytes(expected_path);
  REQUIRE(expected.size() > 1000);
  for (int n : {1, 2, 3}) {
    INFO(n << " ranks");
    const auto out = (dir / ("mpi" + std::to_string(n) + ".ply")).string();
    const auto r = mpirun(n, with({"--threads", "1"}, out));
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    CHECK(test::file_bytes(out) == expected);
  }
}

TEST_CASE("dpts-mpi fails with one line from rank 0 and no output", "[cli][mpi]") {
  test::TempDir dir;
  const std::string dem = hills(dir);
  const auto out = (dir / "out.ply").string();
  struct Case {
    std::vector<std::string> args;
    int code;
    std::string line;
  };
  const std::vector<Case> cases = {
      {{"--algo", "vp", dem, out},
       2,
       "dpts-mpi: --algo vp: dpts-mpi runs the default qem engine only (dpts-par runs the "
       "others); see dpts-mpi --help\n"},
      {{(dir / "missing.tif").string(), out},
       1,
       "dpts-mpi: error: " + (dir / "missing.tif").string()},
      {{"--max-memory", "1", dem, out}, 1, "dpts-mpi: error: " + dem + ": keeping "},
  };
  for (const auto& c : cases) {
    INFO(c.args[0] << " " << c.args[1]);
    const auto r = mpirun(3, c.args);
    CHECK(r.exit_code == c.code);
    CHECK(r.err.rfind(c.line, 0) == 0);
    const auto lines = std::count(r.err.begin(), r.err.end(), '\n');
    CHECK(lines == 1);
    CHECK_FALSE(std::filesystem::exists(out));
  }
}

TEST_CASE("Ctrl-C stops every rank of dpts-mpi, one line and no output", "[cli][mpi][robust]") {
  test::TempDir dir;
  const auto dem = (dir / "dem.tif").string();
  test::write_geotiff(
      dem,
      // note: large enough that the pieces outlast the signal's way through mpirun (1500 x
      // 1500 finished first in 2 of 3 runs once the heap came on huge pages).
      test::make_grid(
          2500, 2500,
          [](int c, int r) { return 500.0 + 40.0 * std::sin(c * 0.05) * std::cos(r * 0.07); }),
      {400000, 10, 0, 3800000, 0, -10}, test::epsg_wkt(32611));
  test::RunOptions ro;
  ro.signal = SIGINT;  // to mpirun, which passes it on to every rank
  ro.signal_when = "simplify";
  ro.signal_after_s = 60;
  const auto r = mpirun(2, {"--threads", "1", dem, (dir / "out.ply").string()}, ro);
  INFO(r.err);
  CHECK(r.exit_code == 1);
  CHECK(r.err.find("dpts-mpi: interrupted; no output written\n") != std::string::npos);
  CHECK(dir.files() == std::vector<std::string>{"dem.tif"});
}

#endif

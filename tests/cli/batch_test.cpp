// dpts-par --report and --batch: machine-readable reports, resumable batches.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/json.hpp"
#include "io/sha256.hpp"
#include "test_support.hpp"

using namespace dpts;
namespace fs = std::filesystem;

namespace {

const std::string kExe = DPTS_PAR_EXE;

std::string field(const std::string& json, const std::string& key) {
  return io::json_field(json, key).value_or("<missing " + key + ">");
}

// A folder of `count` small DEMs (dem0.tif, ...) and one file that is not a raster.
void make_folder(const fs::path& dir, int size, int count = 3) {
  fs::create_directories(dir);
  for (int k = 0; k < count; ++k) {
    test::write_geotiff(dir / ("dem" + std::to_string(k) + ".tif"),
                        test::make_grid(size, size, [k](int c, int r) {
                          return 100.0 * k + 30.0 * std::sin(0.2 * c + k) * std::cos(0.15 * r);
                        }),
                        {400000, 10, 0, 3800000, 0, -10}, test::epsg_wkt(32611));
  }
  std::ofstream(dir / "broken.tif") << "a download cut short\n";
}

}  // namespace

TEST_CASE("sha256 matches the FIPS 180-4 examples", "[io]") {
  CHECK(io::sha256_hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(io::sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(io::sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  CHECK(io::sha256_hex(std::string(1000000, 'a')) ==
        "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST_CASE("json_field reads back what JsonObject writes", "[io]") {
  const std::string json = io::JsonObject()
                               .add("a", "x \"quoted\" \\ line\nbreak")
                               .raw("nested", io::JsonObject().add("bytes", 42).str())
                               .add("n", 1.5)
                               .add("flag", true)
                               .str();
  CHECK(io::json_field(json, "a") == "x \"quoted\" \\ line\nbreak");
  CHECK(io::json_field(json, "nested") == "{\"bytes\":42}");
  CHECK(io::json_field(*io::json_field(json, "nested"), "bytes") == "42");
  CHECK(io::json_field(json, "n") == "1.5");
  CHECK(io::json_field(json, "flag") == "true");
  CHECK_FALSE(io::json_field(json, "bytes"));  // nested fields are not top-level
  CHECK_FALSE(io::json_field("{\"a\":\"unterminated", "a"));
}

TEST_CASE("a run report describes the run, the output's sha256, and a failure", "[cli][report]") {
  test::TempDir dir;
  make_folder(dir.path(), 40);
  const auto out = dir / "out.ply", report = dir / "run.json";
  const auto r = test::run(kExe, {"--algo", "vp-meta", "--levels", "2", "--report",
                                  report.string(), (dir / "dem1.tif").string(), out.string()});
  REQUIRE(r.exit_code == 0);
  const std::string json = test::file_bytes(report);
  CHECK(field(json, "status") == "ok");
  CHECK(field(json, "exit_code") == "0");
  CHECK(field(json, "dpts_version") == DPTS_VERSION);
  const std::string input = field(json, "input"), output = field(json, "output");
  CHECK(field(input, "valid_cells") == "1600");
  CHECK(field(input, "width") == "40");
  CHECK(field(input, "crs").find("UTM zone 11N") != std::string::npos);
  CHECK(field(output, "vertices") == "160");
  CHECK(field(output, "sha256") == io::sha256_file(out.string()));
  CHECK(field(output, "bytes") == std::to_string(fs::file_size(out)));
  CHECK(field(field(json, "options"), "algo") == "vp-meta");
  const std::string stages = field(json, "stages");
  for (const char* stage : {"open", "count", "values", "simplify", "merge", "write"}) {
    CHECK(stages.find(std::string("\"stage\":\"") + stage + "\"") != std::string::npos);
  }
  CHECK(field(json, "pieces").find("\"budget\":") != std::string::npos);
  CHECK(std::stod(field(json, "peak_rss_mb")) > 1.0);

  const auto bad = test::run(kExe, {"--report", report.string(), (dir / "broken.tif").string(),
                                    out.string()});
  CHECK(bad.exit_code == 1);
  const std::string failed = test::file_bytes(report);
  CHECK(field(failed, "status") == "failed");
  CHECK(field(failed, "exit_code") == "1");
  CHECK(field(failed, "error").find("broken.tif: not a raster GDAL can read") != std::string::npos);
  CHECK(field(failed, "output") == "null");
}

TEST_CASE("a batch records the broken input, goes on, and resumes without redoing work",
          "[cli][batch]") {
  test::TempDir dir;
  make_folder(dir / "in", 30);
  const std::vector<std::string> args = {"--batch", (dir / "in").string(), "--out-dir",
                                         (dir / "out").string(), "--algo", "vp"};
  const auto first = test::run(kExe, args);
  CHECK(first.exit_code == 1);  // one input failed
  const std::string summary = test::file_bytes(dir / "out" / "batch-summary.json");
  CHECK(field(summary, "inputs") == "4");
  CHECK(field(summary, "ok") == "3");
  CHECK(field(summary, "failed") == "1");
  CHECK(field(summary, "failures").find("broken.tif: not a raster GDAL can read") !=
        std::string::npos);
  for (int k = 0; k < 3; ++k) {
    const auto report = test::file_bytes(dir / "out" / ("dem" + std::to_string(k) + ".json"));
    CHECK(field(report, "status") == "ok");
    CHECK(field(field(report, "output"), "sha256") ==
          io::sha256_file((dir / "out" / ("dem" + std::to_string(k) + ".ply")).string()));
  }
  CHECK(field(test::file_bytes(dir / "out" / "broken.json"), "status") == "failed");
  CHECK(first.err.find("[1/4] failed") != std::string::npos);

  // Again: the three are skipped, the broken one fails again.
  const auto second = test::run(kExe, args);
  CHECK(second.exit_code == 1);
  const std::string again = test::file_bytes(dir / "out" / "batch-summary.json");
  CHECK(field(again, "skipped") == "3");
  CHECK(field(again, "ok") == "0");
  // One output deleted: only that one is made again.
  fs::remove(dir / "out" / "dem1.ply");
  const auto third = test::run(kExe, args);
  const std::string redo = test::file_bytes(dir / "out" / "batch-summary.json");
  CHECK(field(redo, "skipped") == "2");
  CHECK(field(redo, "ok") == "1");
  CHECK(fs::exists(dir / "out" / "dem1.ply"));
  // Other options: nothing matches, all is redone.
  std::vector<std::string> other = args;
  other.back() = "pld";
  test::run(kExe, other);
  CHECK(field(test::file_bytes(dir / "out" / "batch-summary.json"), "ok") == "3");
  // Once the broken input is gone, the batch succeeds.
  fs::remove(dir / "in" / "broken.tif");
  CHECK(test::run(kExe, other).exit_code == 0);
}

TEST_CASE("a batch with --format writes each output in that format", "[cli][batch][formats]") {
  test::TempDir dir;
  make_folder(dir / "in", 30);
  fs::remove(dir / "in" / "broken.tif");
  const auto r = test::run(kExe, {"--quiet", "--batch", (dir / "in").string(), "--out-dir",
                                  (dir / "out").string(), "--format", "gpkg"});
  CHECK(r.exit_code == 0);
  for (int k = 0; k < 3; ++k) {
    const auto out = dir / "out" / ("dem" + std::to_string(k) + ".gpkg");
    CHECK(test::file_bytes(out).rfind("SQLite format 3", 0) == 0);
    CHECK(field(field(test::file_bytes(dir / "out" / ("dem" + std::to_string(k) + ".json")),
                      "output"),
                "sha256") == io::sha256_file(out.string()));
  }
}

TEST_CASE("a batch folder's tables and vector files are not inputs", "[cli][batch]") {
  test::TempDir dir;
  make_folder(dir / "in", 12, 2);
  fs::remove(dir / "in" / "broken.tif");
  std::ofstream(dir / "in" / "points.csv") << "x,y,z\n400000,3800000,12\n";
  std::ofstream(dir / "in" / "roads.geojson") << R"({"type":"FeatureCollection","features":[]})"
                                              << "\n";
  const auto r = test::run(
      kExe, {"--batch", (dir / "in").string(), "--out-dir", (dir / "out").string(), "--quiet"});
  CHECK(r.exit_code == 0);
  const std::string summary = test::file_bytes(dir / "out" / "batch-summary.json");
  CHECK(field(summary, "inputs") == "2");
  CHECK(field(summary, "ok") == "2");
  CHECK(field(summary, "failed") == "0");
}

TEST_CASE("two batches into one folder: the second is refused while the first runs",
          "[cli][batch][robust]") {
  test::TempDir dir;
  make_folder(dir / "in", 12, 1);
  fs::remove(dir / "in" / "broken.tif");
  const auto out = dir / "out";
  fs::create_directories(out);
  // The first batch's lock, held here.
  const int fd = ::open((out / ".dpts-batch.lock").c_str(), O_RDWR | O_CREAT, 0644);
  REQUIRE(fd >= 0);
  REQUIRE(::flock(fd, LOCK_EX | LOCK_NB) == 0);
  const std::vector<std::string> args = {"--batch", (dir / "in").string(), "--out-dir",
                                         out.string(), "--quiet"};
  const auto second = test::run(kExe, args);
  CHECK(second.exit_code == 1);
  CHECK(second.err ==
        "dpts-par: error: " + out.string() + ": another dpts-par batch is writing into it\n");
  CHECK(!fs::exists(out / "dem0.ply"));
  ::close(fd);  // the first is done
  CHECK(test::run(kExe, args).exit_code == 0);
  CHECK(fs::exists(out / "dem0.ply"));
}

TEST_CASE("a batch child killed mid-run leaves no temporary file, and the batch goes on",
          "[cli][batch][robust]") {
  test::TempDir dir;
  make_folder(dir / "in", 12, 1);
  fs::remove(dir / "in" / "broken.tif");
  // Far more than 3 s of CPU: under a 3 s CPU limit the kernel kills its child (SIGXCPU)
  // after its temporary output exists. 9 M cells: about 19 s of CPU in Release on 2026-11-27,
  // so a kernel several times faster still runs past the limit (1.7 M cells no longer did).
  test::write_geotiff(
      dir / "in" / "big.tif",
      test::make_grid(
          3000, 3000,
          [](int c, int r) { return 500.0 + 40.0 * std::sin(c * 0.05) * std::cos(r * 0.07); }),
      {400000, 10, 0, 3800000, 0, -10}, test::epsg_wkt(32611));
  test::RunOptions ro;
  ro.cpu_limit_s = 3;  // the small DEM needs well under it, sanitizers included
  const auto r = test::run(kExe,
                           {"--batch", (dir / "in").string(), "--out-dir", (dir / "out").string(),
                            "--jobs", "1", "--threads", "2", "--quiet"},
                           ro);
  CHECK(r.exit_code == 1);
  const std::string summary = test::file_bytes(dir / "out" / "batch-summary.json");
  CHECK(field(summary, "ok") == "1");
  CHECK(field(summary, "failed") == "1");
  CHECK(summary.find("dpts-par was killed by signal " + std::to_string(SIGXCPU)) !=
        std::string::npos);
  CHECK(fs::exists(dir / "out" / "dem0.ply"));
  CHECK_FALSE(fs::exists(dir / "out" / "big.ply"));
  for (const auto& entry : fs::directory_iterator(dir / "out")) {
    CHECK(entry.path().filename().string().find(".partial") == std::string::npos);
  }
}

TEST_CASE("batch usage errors exit 2", "[cli][batch]") {
  test::TempDir dir;
  const std::string d = dir.path().string();
  const auto no_out = test::run(kExe, {"--batch", d});
  CHECK(no_out.exit_code == 2);
  CHECK(no_out.err.rfind("dpts-par: --batch: needs --out-dir", 0) == 0);
  const auto jobs = test::run(kExe, {"--jobs", "2", "a.tif", "b.ply"});
  CHECK(jobs.exit_code == 2);
  CHECK(jobs.err.rfind("dpts-par: --jobs: needs --batch", 0) == 0);
  make_folder(dir / "in", 10, 1);
  const std::string raster = (dir / "in" / "dem0.tif").string();
  const auto one = test::run(kExe, {"--batch", raster, "--out-dir", d + "/out"});
  CHECK(one.exit_code == 2);
  CHECK(one.err.rfind("dpts-par: --batch " + raster + ": is a raster, not a folder or a list", 0) ==
        0);
  CHECK(!fs::exists(dir / "out"));
  const auto missing = test::run(kExe, {"--batch", d + "/nothing", "--out-dir", d + "/out"});
  CHECK(missing.exit_code == 2);
  CHECK(missing.err.rfind("dpts-par: --batch " + d + "/nothing: not a folder or a readable list",
                          0) == 0);
}

TEST_CASE("a batch killed by SIGTERM and run again gives the same outputs as one run",
          "[cli][batch]") {
  test::TempDir dir;
  // Six inputs: after the first ends, five are left (a second or more), so the signal lands
  // mid-batch; with three small ones a loaded CI machine once finished the batch first.
  constexpr int kInputs = 6;
  make_folder(dir / "in", 300, kInputs);
  std::filesystem::remove(dir / "in" / "broken.tif");
  {
    std::ofstream list(dir / "list.txt");
    list << "# the DEMs\n";
    for (int k = 0; k < kInputs; ++k) list << "in/dem" << k << ".tif\n";
  }
  auto batch = [&](const std::string& out, const test::RunOptions& ro = {}) {
    return test::run(kExe, {"--batch", (dir / "list.txt").string(), "--out-dir",
                            (dir / out).string(), "--algo", "vp-meta", "--jobs", "2", "--threads",
                            "2"},
                     ro);
  };
  REQUIRE(batch("whole").exit_code == 0);
  test::RunOptions ro;
  ro.signal_when = "[1/6]";  // once the first input has finished
  ro.signal_after_s = 60;
  const auto killed = batch("resumed", ro);
  CHECK(killed.exit_code == 1);
  const std::string summary = test::file_bytes(dir / "resumed" / "batch-summary.json");
  CHECK(field(summary, "interrupted") == "true");
  CHECK(std::stoi(field(summary, "ok")) >= 1);
  for (const auto& entry : fs::directory_iterator(dir / "resumed")) {
    CHECK(entry.path().filename().string().find(".partial") == std::string::npos);
  }
  const auto resumed = batch("resumed");
  CHECK(resumed.exit_code == 0);
  CHECK(std::stoi(field(test::file_bytes(dir / "resumed" / "batch-summary.json"), "skipped")) >= 1);
  for (int k = 0; k < kInputs; ++k) {
    const std::string name = "dem" + std::to_string(k) + ".ply";
    CHECK(io::sha256_file((dir / "whole" / name).string()) ==
          io::sha256_file((dir / "resumed" / name).string()));
  }
}

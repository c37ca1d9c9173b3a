// Every bad or strange input gets a clear answer: the exit code, a one-line message naming the
// file or flag, and no output (or, for strange but valid inputs, a valid output).
#include <catch2/catch.hpp>
#include <filesystem>

#include "cli/bad_inputs.hpp"
#include "core/mesh_check.hpp"
#include "io/ply.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

bool output_files_left(const test::TempDir& dir) {
  for (const auto& name : dir.files()) {
    if (name == "out.ply" || name.find(".partial") != std::string::npos) return true;
  }
  return false;
}

}  // namespace

TEST_CASE("each bad input gets its exit code, a one-line message and no output", "[cli][robust]") {
  test::TempDir dir;
  const auto cases = test::make_bad_inputs(dir.path());
  REQUIRE(cases.size() > 30);
  for (const auto& c : cases) {
    if (c.exit_code == 0) continue;
    INFO(c.what);
    test::RunOptions ro;
    ro.file_size_limit = c.file_size_limit;
    const auto r = test::run(DPTS_PAR_EXE, c.args, ro);
    CHECK(r.exit_code == c.exit_code);
    const std::string prefix = c.exit_code == 2 ? "dpts-par: " : "dpts-par: error: ";
    CHECK(r.err.rfind(prefix + c.message, 0) == 0);
    const auto lines = std::count(r.err.begin(), r.err.end(), '\n');
    CHECK(lines == 1);
    CHECK_FALSE(output_files_left(dir));
  }
}

TEST_CASE("strange but valid inputs give a valid TIN and say what was assumed", "[cli][robust]") {
  test::TempDir dir;
  for (const auto& c : test::make_bad_inputs(dir.path())) {
    if (c.exit_code != 0) continue;
    INFO(c.what);
    std::filesystem::remove(c.output);
    const auto r = test::run(DPTS_PAR_EXE, c.args);
    REQUIRE(r.exit_code == 0);
    if (!c.message.empty()) CHECK(r.err.find("dpts-par: " + c.message) != std::string::npos);
    const io::Mesh mesh = io::read_ply_file(c.output);
    CHECK(mesh.vertex_count() >= 3);
    const core::MeshCheck mc = core::check_mesh(core::xy_of(mesh.xyz), mesh.faces);
    CHECK(mc.clockwise_or_flat == 0);
    CHECK(mc.bad_edges == 0);
    CHECK(mc.area > 0);
  }
}

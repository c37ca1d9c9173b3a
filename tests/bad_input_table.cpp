// Prints, as a Markdown table, what dpts-par answers to each bad or strange input of
// tests/cli/bad_inputs.cpp: exit code, first line of stderr (or the warning expected), and
// whether an output or temporary file was left. Usage: bad_input_table (no arguments).
// note: test_support's checks use Catch2; its implementation, without Catch2's main.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>

#include "cli/bad_inputs.hpp"
#include "test_support.hpp"

int main() {
  using namespace dpts;
  test::TempDir dir;
  std::printf("| input | exit | expected | message (first line of stderr, or the warning) | output left |\n");
  std::printf("|---|---|---|---|---|\n");
  int wrong = 0;
  for (const auto& c : test::make_bad_inputs(dir.path())) {
    std::filesystem::remove(dir / "out.ply");
    test::RunOptions ro;
    ro.file_size_limit = c.file_size_limit;
    const auto r = test::run(DPTS_PAR_EXE, c.args, ro);
    std::string line = r.err.substr(0, r.err.find('\n'));
    if (c.exit_code == 0 && !c.message.empty()) {
      const auto at = r.err.find("dpts-par: " + c.message);
      line = at == std::string::npos ? "(missing: " + c.message + ")"
                                     : r.err.substr(at, r.err.find('\n', at) - at);
    } else if (c.exit_code == 0) {
      line = r.err.substr(r.err.rfind('\n', r.err.size() - 2) + 1);
      line = line.substr(0, line.find('\n'));
    }
    // Temporary folder names vary: show paths relative to it.
    for (auto at = line.find(dir.path().string()); at != std::string::npos;
         at = line.find(dir.path().string())) {
      line.replace(at, dir.path().string().size() + 1, "");
    }
    bool left = false;
    for (const auto& name : dir.files()) left = left || name.find(".partial") != std::string::npos;
    const bool out = std::filesystem::exists(dir / "out.ply");
    const bool as_expected = r.exit_code == c.exit_code && out == (c.exit_code == 0) && !left;
    wrong += as_expected ? 0 : 1;
    std::printf("| %s | %d | %d | %s | %s |\n", c.what.c_str(), r.exit_code, c.exit_code,
                line.c_str(), left ? "TEMPORARY FILE" : out ? "out.ply" : "none");
  }
  std::printf("\n%d of the answers differ from the expected ones\n", wrong);
  return wrong == 0 ? 0 : 1;
}

// The bad and strange inputs dpts-par must answer clearly: made in a folder, each with the
// exit code and the start of the message expected. Shared by the CLI test and by
// bad_input_table (which prints what dpts-par answers, for the robustness report).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace dpts::test {

struct BadInput {
  std::string what;               // the input, in words
  std::vector<std::string> args;  // dpts-par's arguments (output: dir / "out.ply")
  int exit_code = 1;
  std::string message;  // expected start of stderr's first line
  std::string output;   // "" when no output may exist, else the path that must exist
  std::size_t file_size_limit = 0;  // RLIMIT_FSIZE for the run (0: none)
};

// Writes the inputs into `dir` and returns the cases.
std::vector<BadInput> make_bad_inputs(const std::filesystem::path& dir);

}  // namespace dpts::test

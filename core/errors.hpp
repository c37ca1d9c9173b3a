// Error types of dpts: library code throws these, only main() picks an exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace dpts {

// The data is bad: not a raster, all no-data, malformed PLY... (exit code 1).
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The system failed: cannot write, disk full, interrupted... (exit code 1).
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The user asked for something invalid: a bad flag or value (exit code 2).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What a DEM with no triangle of valid cells gets, after its file name (every reader and
// algorithm finds this out on its own, at a different step).
inline constexpr char kNothingToTriangulate[] =
    "no three neighbouring valid cells: nothing to triangulate";

// The run was stopped on request (SIGINT, SIGTERM or a progress callback).
struct Cancelled : std::runtime_error {
  Cancelled() : std::runtime_error("interrupted") {}
};

}  // namespace dpts

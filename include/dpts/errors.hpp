// What dpts throws: one-line messages that name the file or option at fault. The tools map
// them to exit codes (UsageError 2, the others 1); library users catch dpts::Error.
#pragma once

#include <stdexcept>

namespace dpts {

struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The data is bad: not a raster, all no-data, malformed PLY...
struct InputError : Error {
  using Error::Error;
};

// The system failed: cannot write, disk full...
struct IoError : Error {
  using Error::Error;
};

// Something invalid was asked for: a bad option or value.
struct UsageError : Error {
  using Error::Error;
};

// The run was stopped on request (SIGINT, SIGTERM, or a progress callback returning false).
struct Cancelled : Error {
  Cancelled() : Error("interrupted") {}
};

}  // namespace dpts

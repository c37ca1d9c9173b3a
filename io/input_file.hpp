// Inputs that are read as plain files (a mesh, a sample-point table): refused at once when the
// path is missing, a directory, or a FIFO or device (whose open would block with no writer).
#pragma once

#include <filesystem>
#include <string>
#include <system_error>

#include "core/errors.hpp"

namespace dpts::io {

// Throws InputError "PATH: cannot reach (REASON)" when a status query failed otherwise than by
// the path not being there (a folder on the way that may not be entered: Permission denied).
inline void throw_if_unreachable(const std::string& path, const std::error_code& ec) {
  if (ec && ec != std::errc::no_such_file_or_directory && ec != std::errc::not_a_directory) {
    throw InputError(path + ": cannot reach (" + ec.message() + ")");
  }
}

// Throws InputError "PATH: no such file", "PATH: is a directory, not a WHAT" or "PATH: is a
// pipe or a device, not a WHAT file".
inline void check_plain_input(const std::string& path, const std::string& what) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  throw_if_unreachable(path, ec);
  if (!std::filesystem::exists(st)) throw InputError(path + ": no such file");
  if (std::filesystem::is_directory(st)) {
    throw InputError(path + ": is a directory, not a " + what);
  }
  if (!std::filesystem::is_regular_file(st)) {
    throw InputError(path + ": is a pipe or a device, not a " + what + " file");
  }
}

}  // namespace dpts::io

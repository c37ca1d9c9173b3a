// Unnamed temporary files: made and unlinked at once, so that their space is given back
// however the process ends (dpts-par's spilled mesh, dpts-eval's routes).
#pragma once

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace dpts::core {

// The folder of temporary files: TMPDIR, else /tmp.
inline std::string temp_dir() {
  const char* tmp = std::getenv("TMPDIR");
  return tmp != nullptr && *tmp != '\0' ? tmp : "/tmp";
}

// A file made in dir (named stem and six random characters) and unlinked at once: its
// descriptor, or -1 (errno set by mkstemp) where it cannot be made.
inline int unnamed_temp_file(const std::string& dir, const char* stem) {
  std::string name = (std::filesystem::path(dir) / (std::string(stem) + "-XXXXXX")).string();
  const int fd = ::mkstemp(name.data());
  if (fd >= 0) ::unlink(name.c_str());
  return fd;
}

}  // namespace dpts::core

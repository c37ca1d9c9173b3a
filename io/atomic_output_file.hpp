// An output file that appears only complete: written beside its final path, renamed on commit.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace dpts::io {

class AtomicOutputFile {
 public:
  // Creates a new, uniquely named temporary file in final_path's directory (never touching
  // an existing file). Throws IoError naming final_path if the directory is not writable.
  explicit AtomicOutputFile(std::filesystem::path final_path);
  ~AtomicOutputFile();  // not committed: removes the temporary file
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ostream& stream() { return out_; }
  const std::filesystem::path& temp_path() const { return temp_; }
  // Flushes, syncs, checks for write errors, and renames over final_path (replacing it).
  void commit();

 private:
  std::filesystem::path final_;
  std::filesystem::path temp_;
  std::ofstream out_;
  bool committed_ = false;
};

}  // namespace dpts::io

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
  // A symbolic link is written through: the file appears at its target, the link stays. A
  // FIFO, character device or socket (a pipe, /dev/stdout, /dev/null) is not replaced but
  // written into directly, as a stream (what a failed run wrote there stays written); so is
  // a regular file named as one of this process's descriptors (/dev/stdout, /dev/stderr,
  // /dev/fd/N: a shell's redirection), appended to. A folder or a block device is refused.
  explicit AtomicOutputFile(std::filesystem::path final_path);

  // Removes the temporary files a process killed while writing final_path left behind (the
  // ones a crash cannot clean up); returns how many. For a caller that knows no other
  // process writes final_path now (a batch, under its folder's lock).
  static int remove_leftovers(const std::filesystem::path& final_path);

  // Whether final_path (links followed) is written as a stream (see above).
  static bool streams_to(const std::filesystem::path& final_path);
  // Whether final_path names one of this process's descriptors (/dev/stdout, /dev/stderr,
  // /dev/fd/N, /proc/self/fd/N).
  static bool names_descriptor(const std::filesystem::path& final_path);
  ~AtomicOutputFile();  // not committed: removes the temporary file
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ostream& stream() { return out_; }
  // For a writer that creates the file itself (GDAL's GeoPackage): closes the stream, removes
  // the empty temporary file and returns its path, to be created there before commit(). Throws
  // UsageError for an output written as a stream (a database cannot be streamed).
  std::filesystem::path release_path();
  const std::filesystem::path& temp_path() const { return temp_; }
  // Flushes, syncs, checks for write errors, and renames over final_path (replacing it).
  void commit();

 private:
  std::filesystem::path final_;
  std::filesystem::path temp_;
  std::ofstream out_;
  bool committed_ = false;
  bool stream_ = false;    // written into final_ directly
  bool released_ = false;  // release_path(): another writer creates temp_
};

}  // namespace dpts::io

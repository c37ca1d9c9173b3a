// Atomic output files: mkstemp in the target directory, fsync, rename.
#include "io/atomic_output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "core/errors.hpp"

namespace dpts::io {

namespace fs = std::filesystem;

// What a path that names one of this process's open descriptors leads to was opened by the
// caller (a shell's redirection), and is written into, never replaced by a new file.
bool AtomicOutputFile::names_descriptor(const fs::path& path) {
  const std::string p = path.lexically_normal().string();
  if (p == "/dev/stdout" || p == "/dev/stderr") return true;
  for (const std::string prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    if (p.size() > prefix.size() && p.compare(0, prefix.size(), prefix) == 0 &&
        p.find_first_not_of("0123456789", prefix.size()) == std::string::npos) {
      return true;
    }
  }
  return false;
}

namespace {

// The path a link (even a dangling one, or a chain of them) leads to; a path that is no link
// is its own. The output goes there, the link stays.
fs::path follow_links(fs::path path) {
  std::error_code ec;
  for (int hops = 0; hops < 40 && fs::is_symlink(fs::symlink_status(path, ec)); ++hops) {
    const fs::path target = fs::read_symlink(path, ec);
    if (ec) break;
    path = target.is_absolute() ? target : path.parent_path() / target;
  }
  return path;
}

// The temporary name's start, before mkstemp's 6 characters: 16 bytes longer than the
// output's name in all, so a name near the limit of 255 (NAME_MAX) is cut for it, with room
// for the 8 SQLite adds to a GeoPackage's for its journal ("-journal"): a GeoPackage named
// 235 to 255 bytes failed on it ("unable to open database file").
std::string temp_prefix(const fs::path& final_path) {
  constexpr std::size_t kJournal = 8;
  std::string base = final_path.filename().string();
  if (base.size() > 255 - 16 - kJournal) base.resize(255 - 16 - kJournal);
  return "." + base + ".partial-";
}

}  // namespace

bool AtomicOutputFile::streams_to(const fs::path& final_path) {
  std::error_code ec;
  const fs::file_status st = fs::status(final_path, ec);
  return !ec && (fs::is_fifo(st) || fs::is_character_file(st) || fs::is_socket(st) ||
                 (names_descriptor(final_path) && fs::is_regular_file(st)));
}

int AtomicOutputFile::remove_leftovers(const fs::path& final_path) {
  std::error_code ec;
  const fs::path target = follow_links(final_path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  const std::string prefix = temp_prefix(target);
  int removed = 0;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() == prefix.size() + 6 && name.compare(0, prefix.size(), prefix) == 0 &&
        entry.is_regular_file(ec) && fs::remove(entry.path(), ec)) {
      ++removed;
    }
  }
  return removed;
}

AtomicOutputFile::AtomicOutputFile(fs::path final_path) : final_(std::move(final_path)) {
  std::error_code ec;
  if (streams_to(final_)) {
    // note: opened by its own name, not its link's target: /dev/stdout's target in /proc
    // names a pipe ("pipe:[1234]") that only the link opens.
    // A regular file behind a descriptor (2> log.txt) is appended to: its open description's
    // offset is not ours, and writing from 0 would overwrite what is there.
    stream_ = true;
    const bool file = fs::is_regular_file(fs::status(final_, ec));
    out_.open(final_, std::ios::binary | (file ? std::ios::app : std::ios::out));
    if (!out_) {
      throw IoError(final_.string() + ": cannot open output for writing (" + std::strerror(errno) +
                    ")");
    }
    return;
  }
  const fs::file_status st = fs::status(final_, ec);
  if (fs::is_directory(st)) throw IoError(final_.string() + ": is a folder, not an output file");
  if (fs::is_block_file(st)) {
    throw IoError(final_.string() + ": is a block device; refusing to write to it");
  }
  final_ = follow_links(final_);
  // An existing file we may not write is not replaced (as cp and a shell's > refuse it),
  // though its folder would let the rename through.
  if (fs::is_regular_file(fs::status(final_, ec)) && ::access(final_.c_str(), W_OK) != 0) {
    throw IoError(final_.string() + ": cannot write output (" + std::strerror(errno) + ")");
  }
  const auto dir = final_.has_parent_path() ? final_.parent_path() : fs::path(".");
  std::string pattern = (dir / (temp_prefix(final_) + "XXXXXX")).string();
  std::vector<char> name(pattern.begin(), pattern.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) {
    throw IoError(final_.string() + ": cannot create output (" + std::strerror(errno) + ")");
  }
  ::close(fd);
  temp_ = name.data();
  out_.open(temp_, std::ios::binary | std::ios::trunc);
  if (!out_) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
    throw IoError(final_.string() + ": cannot open output for writing");
  }
}

AtomicOutputFile::~AtomicOutputFile() {
  if (committed_ || stream_) return;
  out_.close();
  std::error_code ec;
  std::filesystem::remove(temp_, ec);
}

std::filesystem::path AtomicOutputFile::release_path() {
  if (stream_) {
    throw UsageError(final_.string() + ": a GeoPackage cannot be written to a stream or device");
  }
  out_.close();
  std::error_code ec;
  std::filesystem::remove(temp_, ec);
  released_ = true;
  return temp_;
}

void AtomicOutputFile::commit() {
  if (released_ && !std::filesystem::exists(temp_)) {
    throw IoError(final_.string() + ": write failed (no file was written)");
  }
  if (!released_) {
    out_.flush();
    if (!out_) {
      const int err = errno;
      throw IoError(
          final_.string() + ": write failed" +
          (err ? std::string(" (") + std::strerror(err) + ")" : std::string(" (disk full?)")));
    }
    out_.close();
    if (out_.fail()) throw IoError(final_.string() + ": write failed on close");
  }
  if (stream_) {
    committed_ = true;
    return;
  }
  // note: fsync before rename, so a crash never leaves a renamed but empty file.
  const int fd = ::open(temp_.c_str(), O_RDONLY);
  if (fd >= 0) {
    const int rc = ::fsync(fd);
    ::close(fd);
    if (rc != 0) throw IoError(final_.string() + ": write failed (" + std::strerror(errno) + ")");
  }
  // mkstemp creates 0600: a file replaced keeps its permissions, a new one gets the usual
  // ones (umask applies).
  struct stat old {};
  if (::stat(final_.c_str(), &old) == 0 && S_ISREG(old.st_mode)) {
    ::chmod(temp_.c_str(), old.st_mode & 07777);
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::chmod(temp_.c_str(), 0666 & ~mask);
  }
  std::error_code ec;
  std::filesystem::rename(temp_, final_, ec);
  if (ec)
    throw IoError(final_.string() + ": cannot rename output into place (" + ec.message() + ")");
  committed_ = true;
}

}  // namespace dpts::io

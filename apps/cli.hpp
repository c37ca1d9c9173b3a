// Command-line parsing and progress reporting shared by the dpts executables.
#pragma once

#include <atomic>
#include <charconv>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/elimination.hpp"
#include "core/errors.hpp"
#include "io/mesh_formats.hpp"
#include "parallel/simplify.hpp"

namespace dpts::cli {

struct ParOptions {
  std::string input, output;
  core::EliminationOptions elimination;
  par::KeepTarget keep;
  std::string keep_text = "10%";
  par::Algorithm algo = par::Algorithm::qem;  // --algo
  std::string algo_text = "qem";              // its name
  std::optional<double> max_error;  // --max-error M: vertical error bound (output CRS units)
  std::string max_error_text;       // M as given
  int levels = 4;
  int value_points = 20;
  bool verbose = false;
  int threads = 0;  // 0: all cores
  int tile_mb = 256;
  std::string t_srs;
  int band = 1;
  std::size_t max_memory_mb = 0;  // 0: the memory available when the run starts
  std::string report;             // --report FILE.json
  std::string batch, out_dir;     // --batch LIST|DIR --out-dir OUT
  int jobs = 1;                   // --jobs N: batch inputs at once
  // The arguments a batch passes on to each child: every option that is not about the batch
  // (--batch, --out-dir, --jobs), its threads, memory or report.
  std::vector<std::string> child_args;
  bool ascii = false;
  // --format F, else OUTPUT's extension (PLY for any other name); a batch writes NAME plus the
  // format's extension
  std::optional<io::MeshFormat> format_flag;
  io::MeshFormat format = io::MeshFormat::ply;
  // Said with the input's notes: OUTPUT's extension is none of the formats' (out.tif), so PLY.
  std::string format_note;
  bool quiet = false;
  bool help = false;
  bool version = false;
  std::vector<std::pair<std::string, std::string>> config;  // GDAL config options
};

// Parses a whole number or decimal for a flag: "FLAG TEXT: expected EXPECTED" as a UsageError
// unless all of text is a number >= min.
template <typename T>
T parse_number(const std::string& flag, const std::string& text, T min, const char* expected) {
  T value{};
  const auto res = std::from_chars(text.data(), text.data() + text.size(), value);
  if (res.ec != std::errc() || res.ptr != text.data() + text.size() || !(value >= min)) {
    throw UsageError(flag + " " + text + ": expected " + expected);
  }
  return value;
}

// A message as one line: line breaks (a path may hold them) written \n and \r, other control
// characters as '?'. Errors are one line.
std::string one_line(std::string_view message);

// Whether two paths name the same file (the same inode, or the same path once resolved):
// outputs must not overwrite inputs.
bool same_file(const std::string& a, const std::string& b);

// The first of `files` (a dataset's, io::DemInfo::files) that `path` names, or null: an output
// there would overwrite the input.
const std::string* same_file_in(const std::string& path, const std::vector<std::string>& files);

// Standard streams the caller closed (2>&-) reopened on /dev/null, before any file is opened:
// otherwise an output file could get descriptor 2 and progress text would land in it.
void reopen_closed_std_streams();
// Whether standard stream fd (0-2) was closed when reopen_closed_std_streams ran: OUTPUT - is
// then refused, not written into /dev/null.
bool std_stream_was_closed(int fd);

// The memory a run may use, in bytes: --max-memory, or what the system has available now.
std::size_t memory_limit_bytes(const ParOptions& o);

// Parses dpts-par's arguments. Throws UsageError with a one-line message naming the flag.
ParOptions parse_par(const std::vector<std::string>& args);
std::string par_help();

// Reads a command line for every dpts tool: flags (--name, --name=value, -x) with their
// values, and positional arguments; after "--" every argument is positional.
class ArgReader {
 public:
  explicit ArgReader(const std::vector<std::string>& args) : args_(args) {}
  // Moves to the next argument ("--" itself is skipped); false at the end.
  bool next();
  // Whether the argument is a flag: it starts with '-', is not "-" alone, and comes before "--".
  bool is_flag() const { return flag_; }
  // The argument; for a flag its name, without an inline "=value".
  const std::string& arg() const { return arg_; }
  // The flag's value: its inline one (once), else the next argument (UsageError "FLAG: missing
  // value").
  std::string value();
  // The arguments the current one took as given: itself, and its value if that came next.
  std::vector<std::string> taken() const {
    return {args_.begin() + static_cast<long>(first_), args_.begin() + static_cast<long>(i_) + 1};
  }

 private:
  const std::vector<std::string>& args_;
  std::size_t i_ = 0, first_ = 0;
  bool started_ = false, flag_ = false, done_ = false, has_inline_ = false;
  std::string arg_, inline_;
};

// Prints "<prog>: <stage> NN%" to stderr once a run has lasted a second: rewriting one line
// on a terminal, one line per 10 % otherwise. Returns false once a cancel was requested.
class ProgressPrinter {
 public:
  ProgressPrinter(std::string prog, bool quiet, const std::atomic<int>* cancel_flag);
  bool operator()(double fraction, std::string_view stage);
  void finish();  // ends a pending terminal line

 private:
  std::string prog_;
  bool quiet_;
  bool tty_;
  const std::atomic<int>* cancel_;
  std::chrono::steady_clock::time_point start_;
  std::string stage_;
  int last_decile_ = -1;
  int last_percent_ = -1;
  bool line_open_ = false;
};

}  // namespace dpts::cli

// Command-line parsing and progress reporting for dpts-par.
#include "apps/cli.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <iterator>

#include "core/errors.hpp"
#include "io/atomic_output_file.hpp"
#include "parallel/memory.hpp"

namespace dpts::cli {

std::string one_line(std::string_view message) {
  std::string out;
  out.reserve(message.size());
  for (const char c : message) {
    if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      out += '?';
    } else {
      out += c;
    }
  }
  return out;
}

bool same_file(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::exists(b, ec) && std::filesystem::equivalent(a, b, ec)) return true;
  return std::filesystem::weakly_canonical(a, ec) == std::filesystem::weakly_canonical(b, ec);
}
const std::string* same_file_in(const std::string& path, const std::vector<std::string>& files) {
  for (const std::string& f : files) {
    if (same_file(path, f)) return &f;
  }
  return nullptr;
}

namespace {
bool g_closed_at_start[3] = {false, false, false};
}  // namespace

bool std_stream_was_closed(int fd) { return fd >= 0 && fd <= 2 && g_closed_at_start[fd]; }

void reopen_closed_std_streams() {
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1 || errno != EBADF) continue;
    g_closed_at_start[fd] = true;
    const int null = ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
    if (null >= 0 && null != fd) {
      ::dup2(null, fd);
      ::close(null);
    }
  }
}

std::string par_help() {
  return R"(usage: dpts-par [options] INPUT OUTPUT
       dpts-par --batch LIST|DIR --out-dir OUT [--jobs N] [options]

Simplifies a DEM (a band of any raster GDAL reads) into a TIN that preserves surface
(geodesic) distances, and writes it as PLY, OBJ, STL or GeoPackage. OUTPUT - is standard
output; INPUT - is standard input (GDAL's /vsistdin/).

  --algo ALGO          qem (default): dpts's quadric edge collapse (triangle quadrics, a
                       cost that sees surface area, the outline's straight runs simplified
                       too, the footprint kept exactly, no folds), out of core: pieces are
                       read and collapsed concurrently with their seams locked, then
                       stitched and collapsed on in one order; the best distances measured
                       (README, Which algorithm).
                       The DPTS paper's Delaunay vertex elimination: vp: importance =
                       volume between the surfaces before and after a removal; pld:
                       preserve local distances (both whole DEM in memory); vp-meta,
                       pld-meta: the paper's VP' and PLD' (k-d pieces, per-piece budgets
                       from the pieces' mean ED/GD), out of core: pieces are read,
                       simplified and freed concurrently, and only the kept vertices are
                       merged. qslim: Garland-Heckbert quadric edge collapse (the paper's
                       competitor) with the outline locked and no folds, in memory
  --levels C           vp-meta/pld-meta/qem: at least 2^C pieces (default 4)
  --value-points L     vp-meta/pld-meta: random points per piece value (default 20)
  --verbose            vp-meta/pld-meta/qem: print every piece's value and budget, and times
  --keep P%            keep P percent of the input vertices, 0 < P <= 100 (default 10%)
  --vertices N         keep N vertices instead (N >= 3)
  --max-error M        qem: keep the vertical error at every valid cell centre <= M metres
                       (heights are metres in any CRS); with --keep or --vertices both
                       bounds hold (the count may then be exceeded), alone as few vertices
                       as M allows
  --vp-volume exact|mc VP volume: exact integral over the hole (default) or the paper's
                       Monte Carlo estimate
  --vp-samples N       Monte Carlo points per VP evaluation (default 100)
  --seed S             seed for the random parts (default 1)
  --t-srs CRS          output CRS (projected); default: the DEM's own CRS if projected,
                       the UTM zone of its centre if geographic
  --threads N          worker threads (default: all cores)
  --tile-mb M          vp-meta/pld-meta/qem: memory budget of one piece in MB (default 256);
                       qem's peak memory is about threads x M whatever the DEM's size (its
                       merge takes one M of pieces at a time, and its mesh goes to TMPDIR
                       as it is made); vp-meta/pld-meta's, that plus the kept vertices. vp
                       and pld read the whole DEM
  --band B             the band holding the heights (default 1)
  --max-memory MB      refuse, before reading the heights, a run estimated to need more
                       memory than MB (default: the memory available when it starts)
  --report FILE.json   write a JSON report of the run (input, options, output with its
                       sha256, per-stage wall and CPU times, peak memory, pieces), also
                       when it fails (not when the command line cannot be read)
  --format F           output format: ply (default), obj (Wavefront), stl (binary; float32
                       coordinates) or gpkg (GeoPackage: one layer of triangles as Polygon Z
                       features, with the CRS; opens in QGIS); default: OUTPUT's extension
                       (.ply .obj .stl .gpkg), else ply
  --ascii              write ASCII PLY or STL (default: binary little-endian)
  --config KEY VALUE   set a GDAL configuration option
  --quiet              no progress or summary on stderr (warnings still show)
  --help, --version

Batch mode: dpts-par --batch LIST|DIR --out-dir OUT [--jobs N] [options]
  simplifies every raster of folder DIR (or every path listed in file LIST, one per line)
  into OUT/NAME.ply (or the --format's extension) with OUT/NAME.json reports, and writes
  OUT/batch-summary.json. A failed input is recorded and the batch goes on. Run it again to
  resume: inputs whose report says ok for the same input (size, modification time) and
  options are skipped. --jobs N runs N inputs at once, sharing --threads between them.
  Exit 0 only when every input is done.

Every valid cell centre is a vertex; no-data, NaN, infinite and absurd (beyond +-1e7)
heights are not, and no face covers a void or leaves the valid data (-9999, -32768 and
other usual no-data values not the band's are heights, with a warning). Heights are
the band's values with its scale and offset applied; any real cell type is read. Output:
vertex x y z (double, output CRS), faces counter-clockwise seen from above, the CRS as
WKT in a header comment (PLY, OBJ) or in the layer (GeoPackage; STL has none). The output
file appears only when complete. Exit status: 0 ok, 1 failure, 2 bad usage.
)";
}

bool ArgReader::next() {
  if (started_) ++i_;
  started_ = true;
  if (!done_ && i_ < args_.size() && args_[i_] == "--") {
    done_ = true;
    ++i_;
  }
  if (i_ >= args_.size()) return false;
  first_ = i_;
  arg_ = args_[i_];
  flag_ = !done_ && arg_.size() > 1 && arg_[0] == '-';
  has_inline_ = false;
  if (flag_ && arg_.rfind("--", 0) == 0) {
    const auto eq = arg_.find('=');
    if (eq != std::string::npos) {
      inline_ = arg_.substr(eq + 1);
      arg_.resize(eq);
      has_inline_ = true;
    }
  }
  return true;
}

std::string ArgReader::value() {
  if (has_inline_) {
    has_inline_ = false;  // taken: a second value is the next argument
    return inline_;
  }
  if (i_ + 1 >= args_.size()) throw UsageError(arg_ + ": missing value");
  return args_[++i_];
}

namespace {

// Which of --keep and --vertices were given (one, not both; neither: 10 %).
struct KeepSeen {
  bool keep = false, vertices = false;
};

// The method's flags (--algo, its options, what to keep): false if arg is none of them.
bool read_method_flag(const std::string& arg, ArgReader& in, ParOptions& o, KeepSeen& seen) {
  if (arg == "--algo") {
    const std::string v = in.value();
    const auto algo = par::parse_algorithm(v);
    if (!algo) {
      throw UsageError("--algo " + v + ": expected vp, pld, vp-meta, pld-meta, qslim or qem");
    }
    o.algo = *algo;
    o.elimination.importance = par::importance_of(o.algo);
    o.algo_text = v;
  } else if (arg == "--levels") {
    o.levels = parse_number<int>(arg, in.value(), 0, "an integer from 0 to 16");
    if (o.levels > 16)
      throw UsageError("--levels " + std::to_string(o.levels) +
                       ": expected an integer from 0 to 16");
  } else if (arg == "--value-points") {
    o.value_points = parse_number<int>(arg, in.value(), 2, "an integer >= 2");
  } else if (arg == "--verbose" || arg == "-v") {
    o.verbose = true;
  } else if (arg == "--keep") {
    std::string v = in.value();
    o.keep_text = v;
    if (!v.empty() && v.back() == '%') v.pop_back();
    double p = 0;
    const auto res = std::from_chars(v.data(), v.data() + v.size(), p);
    if (v.empty() || res.ec != std::errc() || res.ptr != v.data() + v.size() || !(p > 0) ||
        p > 100) {
      throw UsageError("--keep " + o.keep_text + ": expected a percentage with 0 < P <= 100");
    }
    o.keep.percent = p;
    seen.keep = true;
  } else if (arg == "--max-error") {
    const std::string v = in.value();
    double m = 0;
    const auto res = std::from_chars(v.data(), v.data() + v.size(), m);
    if (v.empty() || res.ec != std::errc() || res.ptr != v.data() + v.size() || !(m > 0) ||
        !std::isfinite(m)) {
      throw UsageError("--max-error " + v + ": expected a positive number (metres)");
    }
    o.max_error = m;
    o.max_error_text = v;
  } else if (arg == "--vertices") {
    const std::string v = in.value();
    o.keep.vertices = parse_number<std::size_t>(arg, v, 3, "an integer >= 3");
    o.keep_text = v + " vertices";
    seen.vertices = true;
  } else if (arg == "--vp-volume") {
    const std::string v = in.value();
    if (v == "exact") {
      o.elimination.vp_volume = core::VolumeMethod::exact;
    } else if (v == "mc") {
      o.elimination.vp_volume = core::VolumeMethod::monte_carlo;
    } else {
      throw UsageError("--vp-volume " + v + ": expected exact or mc");
    }
  } else if (arg == "--vp-samples") {
    o.elimination.vp_samples = parse_number<int>(arg, in.value(), 1, "an integer >= 1");
  } else if (arg == "--seed") {
    o.elimination.seed = parse_number<std::uint64_t>(arg, in.value(), 0, "a non-negative integer");
  } else {
    return false;
  }
  return true;
}

// The run's flags (threads, memory, input, output, batch, GDAL): false if arg is none of them.
bool read_run_flag(const std::string& arg, ArgReader& in, ParOptions& o) {
  if (arg == "--threads") {
    o.threads = parse_number<int>(arg, in.value(), 1, "an integer >= 1");
  } else if (arg == "--tile-mb") {
    o.tile_mb = parse_number<int>(arg, in.value(), 1, "an integer >= 1");
  } else if (arg == "--t-srs") {
    o.t_srs = in.value();
    if (o.t_srs.empty()) throw UsageError("--t-srs: expected a CRS");
  } else if (arg == "--band") {
    o.band = parse_number<int>(arg, in.value(), 1, "an integer >= 1");
  } else if (arg == "--max-memory") {
    o.max_memory_mb = parse_number<std::size_t>(arg, in.value(), 1, "an integer >= 1 (MB)");
  } else if (arg == "--report") {
    o.report = in.value();
    if (o.report.empty()) throw UsageError("--report: expected a file name");
  } else if (arg == "--batch") {
    o.batch = in.value();
    if (o.batch.empty()) throw UsageError("--batch: expected a folder or a list file");
  } else if (arg == "--out-dir") {
    o.out_dir = in.value();
    if (o.out_dir.empty()) throw UsageError("--out-dir: expected a folder");
  } else if (arg == "--jobs") {
    o.jobs = parse_number<int>(arg, in.value(), 1, "an integer >= 1");
  } else if (arg == "--ascii") {
    o.ascii = true;
  } else if (arg == "--format") {
    const std::string text = in.value();
    o.format_flag = io::parse_mesh_format(text);
    if (!o.format_flag) throw UsageError("--format " + text + ": expected ply, obj, stl or gpkg");
  } else if (arg == "--quiet" || arg == "-q") {
    o.quiet = true;
  } else if (arg == "--config") {
    std::string key, value;
    try {
      key = in.value();
      value = in.value();
    } catch (const UsageError&) {
      throw UsageError("--config: expected KEY VALUE");
    }
    o.config.emplace_back(key, value);
  } else {
    return false;
  }
  return true;
}

// The checks across flags and the positional arguments, once all are read.
void check_par(ParOptions& o, const std::vector<std::string>& positional, const KeepSeen& seen) {
  if (seen.keep && seen.vertices) throw UsageError("--keep and --vertices: give one, not both");
  if (o.max_error && o.algo != par::Algorithm::qem) {
    throw UsageError("--max-error: only with --algo qem");
  }
  if (!seen.keep && !seen.vertices) {
    if (o.max_error) {
      // The error bound alone: as few vertices as it allows.
      o.keep.vertices = 3;
      o.keep_text = "none";
    } else {
      o.keep.percent = 10.0;
    }
  }
  if (o.ascii && o.format_flag == io::MeshFormat::gpkg) {
    throw UsageError("--ascii: a GeoPackage has no ASCII form");
  }
  if (!o.batch.empty() || !o.out_dir.empty()) {
    o.format = o.format_flag.value_or(io::MeshFormat::ply);
    if (o.batch.empty()) throw UsageError("--out-dir: needs --batch");
    if (o.out_dir.empty()) throw UsageError("--batch: needs --out-dir");
    if (!o.report.empty()) throw UsageError("--report: a batch writes one report per input");
    if (!positional.empty())
      throw UsageError("unexpected argument '" + positional[0] + "' with --batch");
    return;
  }
  if (o.jobs != 1) throw UsageError("--jobs: needs --batch");
  if (positional.size() != 2) {
    throw UsageError(positional.size() < 2 ? "expected INPUT and OUTPUT"
                                           : "unexpected argument '" + positional[2] + "'");
  }
  for (const int k : {0, 1}) {
    if (positional[static_cast<std::size_t>(k)].empty()) {
      throw UsageError(std::string(k == 0 ? "INPUT" : "OUTPUT") + " is an empty name");
    }
  }
  // "-": the standard streams, as other tools take it.
  o.input = positional[0] == "-" ? "/vsistdin/" : positional[0];
  o.output = positional[1] == "-" ? "/dev/stdout" : positional[1];
  o.format = o.format_flag.value_or(io::mesh_format_of(o.output));
  // note: a name without an extension (or a stream) is PLY without a word; out.tif or out.xyz
  // may be a slip, and a PLY under such a name surprises whoever opens it.
  const std::string ext = std::filesystem::path(o.output).extension().string();
  if (!o.format_flag && ext.size() > 1 && !io::parse_mesh_format(std::string_view(ext).substr(1)) &&
      !io::AtomicOutputFile::streams_to(o.output)) {
    o.format_note = o.output + ": written as PLY (" + ext +
                    " is not .ply, .obj, .stl or .gpkg; --format picks the format)";
  }
  if (o.format == io::MeshFormat::gpkg) {
    if (o.ascii) throw UsageError("--ascii: a GeoPackage has no ASCII form");
    if (io::AtomicOutputFile::streams_to(o.output)) {
      throw UsageError(positional[1] + ": a GeoPackage cannot be written to a stream or device");
    }
  }
  if (!o.report.empty() && (same_file(o.report, o.input) || same_file(o.report, o.output))) {
    throw UsageError("--report " + o.report + ": is the " +
                     (same_file(o.report, o.input) ? "INPUT" : "OUTPUT") +
                     " file; refusing to overwrite it");
  }
}

}  // namespace

ParOptions parse_par(const std::vector<std::string>& args) {
  ParOptions o;
  std::vector<std::string> positional;
  KeepSeen seen;
  ArgReader in(args);
  while (in.next()) {
    const std::string arg = in.arg();
    if (!in.is_flag()) {
      positional.push_back(arg);
      continue;
    }
    if (arg == "--help" || arg == "-h") {
      o.help = true;
    } else if (arg == "--version") {
      o.version = true;
    } else if (!read_method_flag(arg, in, o, seen) && !read_run_flag(arg, in, o)) {
      throw UsageError(arg + ": unknown option");
    }
    static const char* batch_only[] = {"--batch",      "--out-dir", "--jobs",  "--threads",
                                       "--max-memory", "--report",  "--quiet", "-q"};
    if (std::find(std::begin(batch_only), std::end(batch_only), arg) == std::end(batch_only)) {
      const std::vector<std::string> taken = in.taken();
      o.child_args.insert(o.child_args.end(), taken.begin(), taken.end());
    }
  }
  if (o.help || o.version) return o;
  check_par(o, positional, seen);
  return o;
}

std::size_t memory_limit_bytes(const ParOptions& o) {
  return o.max_memory_mb > 0 ? o.max_memory_mb << 20 : par::available_memory_bytes();
}

ProgressPrinter::ProgressPrinter(std::string prog, bool quiet, const std::atomic<int>* cancel_flag)
    : prog_(std::move(prog)),
      quiet_(quiet),
      tty_(::isatty(2) != 0),
      cancel_(cancel_flag),
      start_(std::chrono::steady_clock::now()) {}

bool ProgressPrinter::operator()(double fraction, std::string_view stage) {
  if (cancel_ && cancel_->load(std::memory_order_relaxed)) return false;
  if (quiet_) return true;
  if (stage != stage_) {
    stage_ = std::string(stage);
    last_decile_ = -1;
    last_percent_ = -1;
  }
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  if (elapsed < 1.0) return true;
  const int percent = static_cast<int>(fraction * 100.0 + 1e-9);
  if (tty_) {
    if (percent != last_percent_) {
      std::fprintf(stderr, "\r%s: %-11s %3d%%", prog_.c_str(), stage_.c_str(), percent);
      std::fflush(stderr);
      line_open_ = true;
      last_percent_ = percent;
    }
  } else if (percent / 10 != last_decile_) {
    last_decile_ = percent / 10;
    std::fprintf(stderr, "%s: %s %d%%\n", prog_.c_str(), stage_.c_str(), last_decile_ * 10);
  }
  return true;
}

void ProgressPrinter::finish() {
  if (line_open_) std::fputc('\n', stderr);
  line_open_ = false;
}

}  // namespace dpts::cli

// dpts-par: simplify a DEM into a distance-preserving TIN (PLY). Thin: parse, call, report.
// Built a second time with DPTS_MPI as dpts-mpi: the same options and output, the qem engine's
// pieces spread over MPI ranks (apps/mpi_pieces.hpp).
#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

#include "api/simplification.hpp"
#include "apps/batch.hpp"
#include "apps/cli.hpp"
#include "apps/report.hpp"
#include "core/errors.hpp"
#include "io/atomic_output_file.hpp"
#include "io/dem_reader.hpp"
#include "io/mesh_formats.hpp"
#include "parallel/memory.hpp"
#include "parallel/meta.hpp"
#include "parallel/qem_engine.hpp"
#include "parallel/simplify.hpp"

#ifdef DPTS_MPI
#include "apps/mpi_pieces.hpp"
#define DPTS_PROG "dpts-mpi"
#else
#define DPTS_PROG "dpts-par"
#endif

namespace {

// Set by SIGINT/SIGTERM, read by every thread: a lock-free atomic (signal-safe, and no data
// race for the worker threads that poll it; TSan flagged the volatile ints this replaces).
std::atomic<int> g_cancel{0};
static_assert(std::atomic<int>::is_always_lock_free);
extern "C" void on_signal(int) { g_cancel.store(1, std::memory_order_relaxed); }

dpts::io::DemReadOptions read_options(const dpts::cli::ParOptions& o) {
  dpts::io::DemReadOptions r;
  r.t_srs = o.t_srs;
  r.band = o.band;
  return r;
}

dpts::cli::RunReport g_report;  // --report: filled as the run goes, written by main()

// Opens the input DEM. An OUTPUT or --report that is one of its dataset's files (an ENVI
// .hdr, a VRT's source raster, the zip behind /vsizip/) is refused like OUTPUT == INPUT:
// writing it would destroy the input.
dpts::io::DemInfo open_input(const dpts::cli::ParOptions& o) {
  using namespace dpts;
  io::DemInfo dem = io::open_dem(o.input, read_options(o));
  if (const std::string* f = cli::same_file_in(o.output, dem.files)) {
    throw UsageError(o.output + ": OUTPUT is " + *f +
                     ", a file of the INPUT dataset; refusing to overwrite it");
  }
  if (const std::string* f = o.report.empty() ? nullptr : cli::same_file_in(o.report, dem.files)) {
    g_report.path.clear();  // nor is the failure written there
    throw UsageError(o.report + ": --report names " + *f +
                     ", a file of the INPUT dataset; refusing to overwrite it");
  }
  return dem;
}

// Records the output in the report: OUTPUT's bytes as written in file (OUTPUT once committed).
void record_output(const dpts::cli::ParOptions& o, const dpts::io::DemInfo& dem,
                   std::size_t valid_cells, std::size_t surface, std::size_t kept,
                   std::size_t faces, const std::string& file) {
  if (g_report.path.empty()) return;
  g_report.input_json = dpts::cli::input_json(dem, valid_cells, surface);
  g_report.output_json = dpts::cli::output_json(o.output, kept, faces, file);
}

void print_notes(const std::vector<std::string>& notes, const dpts::cli::ParOptions& o) {
  for (const std::string& note : notes) {
    if (!o.quiet || note.rfind("warning", 0) == 0) std::cerr << DPTS_PROG ": " << note << "\n";
  }
}

// note: qslim locks every outline vertex (the paper's competitor as QSlim runs it), a
// straight run's too; the other modes keep the outline's corners and bends only.
// note: qem's merge in several groups shares the target among them by the pieces' sizes, so a
// group whose outline needs more than its share keeps more, where one group would have taken
// them from elsewhere (docs/results.md, "What the groups cost").
void warn_kept(std::size_t kept, std::size_t target, bool whole_outline, std::size_t groups) {
  if (kept <= target) return;
  std::cerr << DPTS_PROG ": warning: kept " << kept << " vertices, not " << target << ": "
            << (whole_outline ? "qslim keeps every vertex of the outline of the valid data"
                              : "the outline of the valid data (its corners and the bends "
                                "round voids) needs them");
  if (groups > 1) {
    std::cerr << "; the merge took the pieces in " << groups
              << " parts, each held to its share of the target (--tile-mb sets how many)";
  }
  std::cerr << "\n";
}

void summary(const dpts::cli::ParOptions& o, std::size_t in, std::size_t kept, std::size_t faces,
             std::chrono::steady_clock::time_point start) {
  if (o.quiet) return;
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::fprintf(stderr, DPTS_PROG ": %zu vertices -> %zu vertices, %zu faces (%s, %.2f s) -> %s\n",
               in, kept, faces, o.algo_text.c_str(), secs, o.output.c_str());
}

// Writes a mesh (x, y in the output CRS) in the output format.
void write_mesh(const dpts::cli::ParOptions& o, const dpts::io::DemInfo& dem,
                dpts::api::Simplification& result, dpts::io::AtomicOutputFile& out) {
  using namespace dpts;
  std::string generated = std::string("generated by dpts-par ") + DPTS_VERSION + " --algo " +
                          o.algo_text + " --keep " + o.keep_text;
  if (o.max_error) generated += " --max-error " + o.max_error_text;
  if (par::is_meta(o.algo) || o.algo == par::Algorithm::qem) {
    generated +=
        " --levels " + std::to_string(o.levels) + " --tile-mb " + std::to_string(o.tile_mb);
  }
  if (par::is_meta(o.algo)) generated += " --value-points " + std::to_string(o.value_points);
  io::Mesh mesh;  // the comments; its vertices and faces, unless the mesh was spilled
  mesh.comments.push_back(generated + " from " +
                          std::filesystem::path(o.input).filename().string());
  mesh.comments.push_back("crs " + (dem.output_wkt.empty() ? std::string("none") : dem.output_wkt));
  g_report.clock.enter("write");
  io::MeshWriteOptions wo;
  wo.format = o.format;
  wo.ascii = o.ascii;
  wo.crs_wkt = dem.output_wkt;
  wo.layer = std::filesystem::path(o.output).stem().string();
  double moved = 0;
  try {
    if (result.spilled) {
      moved = io::write_mesh(out, *result.spilled, mesh.comments, wo);
    } else {
      static_cast<core::TriMesh&>(mesh) = std::move(result.mesh);
      moved = io::write_mesh(out, mesh, wo);
    }
  } catch (const IoError& e) {
    throw IoError(o.output + ": " + e.what());
  }
  // note: binary STL holds float32; at UTM northings (~5e6 m) that is 0.25 m steps.
  if (moved > 1e-3) {
    std::fprintf(stderr,
                 DPTS_PROG
                 ": warning: %s: binary STL holds float32: coordinates moved by up to "
                 "%.3g; --ascii keeps them exact\n",
                 o.output.c_str(), moved);
  }
  if (g_cancel.load(std::memory_order_relaxed)) throw Cancelled();
}

// --verbose: the pieces (value: vp-meta/pld-meta's piece values, else "-"), stage times and
// memory.
void print_pieces(const dpts::par::MetaStats& stats, bool values) {
  std::fprintf(stderr,
               DPTS_PROG ": %zu pieces (blocks of %d cells), %zu surface vertices, keep %zu\n",
               stats.pieces.size(), stats.block, stats.input_vertices, stats.target_vertices);
  std::fprintf(stderr, DPTS_PROG
               ": piece  col0  row0 width height vertices    value   P2L%%  budget    "
               "kept  read_s  simpl_s\n");
  for (std::size_t i = 0; i < stats.pieces.size(); ++i) {
    const auto& p = stats.pieces[i];
    char value[16] = "       -";
    if (values) std::snprintf(value, sizeof value, "%8.6f", p.value);
    std::fprintf(stderr, DPTS_PROG ": %5zu %5d %5d %5d %6d %8zu %s %6.2f %7zu %7zu %7.2f %8.2f\n",
                 i, p.piece.col0, p.piece.row0, p.piece.width, p.piece.height, p.piece.vertices,
                 value, 100.0 * p.budget / std::max<std::size_t>(1, p.piece.vertices), p.budget,
                 p.kept, p.read_s, p.simplify_s);
  }
  double longest = 0, sum = 0;
  for (const auto& p : stats.pieces) {
    longest = std::max(longest, p.read_s + p.simplify_s);
    sum += p.read_s + p.simplify_s;
  }
  std::fprintf(stderr,
               DPTS_PROG
               ": pieces: longest %.3f s, mean %.3f s (read + simplify); peak memory "
               "before the merge %.1f MB, of which kept vertices %.1f MB\n",
               longest, sum / static_cast<double>(std::max<std::size_t>(1, stats.pieces.size())),
               static_cast<double>(stats.peak_rss_before_merge_kb) / 1024.0,
               static_cast<double>(stats.kept_bytes) / (1 << 20));
  if (stats.pilot_pieces > 0) {
    if (stats.piece_cost_bound >= 0) {
      std::fprintf(stderr,
                   DPTS_PROG ": pilot: %zu pieces (%zu finished there), %.2f s: the pieces "
                             "collapse while a collapse costs at most %.6g",
                   stats.pilot_pieces, stats.pilot_finished, stats.pilot_s,
                   stats.piece_cost_bound);
      if (stats.merge_cost_cap > 0)
        std::fprintf(stderr, ", the merge never one over %.6g", stats.merge_cost_cap);
      std::fputc('\n', stderr);
      if (stats.pilot_kept_per_outline != stats.pilot_kept_per_inner) {
        std::fprintf(stderr,
                     DPTS_PROG ": pilot: a piece keeps %.3g of its vertices beside no void, %.3g "
                               "of those beside one (%.3g at any cost)\n",
                     stats.pilot_kept_per_inner, stats.pilot_kept_per_outline,
                     stats.pilot_forced_per_outline);
      }
    } else {
      std::fprintf(stderr,
                   DPTS_PROG ": pilot: %zu pieces (%zu finished there), %.2f s: no cost bound "
                             "(each piece keeps its share by size)\n",
                   stats.pilot_pieces, stats.pilot_finished, stats.pilot_s);
    }
  }
  std::fprintf(stderr,
               DPTS_PROG ": stages: count %.2f s, values %.2f s, simplify %.2f s, merge %.2f s",
               stats.count_s, stats.values_s, stats.simplify_s, stats.merge_s);
  if (stats.merge_groups > 1) std::fprintf(stderr, " (in %zu groups)", stats.merge_groups);
  if (stats.premerge_collapses > 0) {
    std::fprintf(stderr, " (pre-merge %.2f s, %zu collapses)", stats.premerge_s,
                 stats.premerge_collapses);
  }
  std::fputc('\n', stderr);
}

// After the method ran: the piece engines' warnings of the heights (their count pass finds them;
// a whole-DEM read's are among the input's notes), --verbose's piece table or qslim's refusals,
// and the kept-count warning.
void after_simplify(const dpts::cli::ParOptions& o, const dpts::api::Simplification& r) {
  if (r.piece_engine) {
    for (const std::string& w : r.height_warnings) std::cerr << DPTS_PROG ": " << w << "\n";
  }
  if (o.verbose && r.piece_engine) print_pieces(r.pieces, dpts::par::is_meta(o.algo));
  if (o.verbose && o.algo == dpts::par::Algorithm::qslim) {
    std::fprintf(stderr, DPTS_PROG ": %s: %zu collapses refused (fold or link condition)\n",
                 o.algo_text.c_str(), r.rejected_folds);
  }
  if (!o.max_error) {
    warn_kept(r.kept_vertices, r.target_vertices, o.algo == dpts::par::Algorithm::qslim,
              r.piece_engine ? r.pieces.merge_groups : 0);
  } else if (r.kept_vertices > r.target_vertices && o.keep_text != "none" && !o.quiet) {
    std::cerr << DPTS_PROG ": kept " << r.kept_vertices << " vertices, not " << r.target_vertices
              << ": --max-error " << o.max_error_text << " needs them\n";
  }
}

bool g_user_cache = false;  // GDAL_CACHEMAX came from the environment

// The piece engines' tile budget in bytes. GDAL's block cache is shared by all pieces'
// handles: a quarter of one tile, 4-64 MB, unless the user set GDAL_CACHEMAX.
std::size_t piece_cache(const dpts::cli::ParOptions& o) {
  const std::size_t tile_bytes = static_cast<std::size_t>(o.tile_mb) << 20;
  bool cache_set = g_user_cache;
  for (const auto& kv : o.config) cache_set = cache_set || kv.first == "GDAL_CACHEMAX";
  if (!cache_set) {
    GDALSetCacheMax64(std::clamp<GIntBig>(static_cast<GIntBig>(tile_bytes / 4), GIntBig{4} << 20,
                                          GIntBig{64} << 20));
  }
  return tile_bytes;
}

// GDAL's settings for the run: --config's, and standard input kept whole.
void apply_config(const dpts::cli::ParOptions& o) {
  // A raster on standard input is read more than once (opened, then piece by piece): GDAL
  // keeps all of it, not its default first 1 MB, unless the user says otherwise.
  if (o.input.rfind("/vsistdin", 0) == 0 &&
      !CPLGetConfigOption("CPL_VSISTDIN_BUFFER_LIMIT", nullptr)) {
    CPLSetConfigOption("CPL_VSISTDIN_BUFFER_LIMIT", "-1");
  }
  for (const auto& [key, value] : o.config) CPLSetConfigOption(key.c_str(), value.c_str());
}

#ifdef DPTS_MPI
// The qem engine's options on ranks other than 0: those api::simplify gives rank 0's engine.
dpts::par::QemEngineOptions qem_options(const dpts::cli::ParOptions& o) {
  dpts::par::QemEngineOptions qo;
  qo.keep = o.keep;
  qo.levels = o.levels;
  qo.tile_bytes = piece_cache(o);
  qo.memory_limit_bytes = dpts::cli::memory_limit_bytes(o);
  if (o.max_error) qo.max_error = *o.max_error;
  return qo;
}

// Rank 0's qem engine: plans (as every rank does), gives the word, simplifies its own share of
// the pieces while the other ranks simplify theirs, receives them and merges all in piece
// order: the same mesh as simplify_qem's in one process.
dpts::core::TriMesh simplify_qem_ranks(const dpts::core::RasterSource& source,
                                       const dpts::par::QemEngineOptions& qo,
                                       const dpts::core::Progress& progress,
                                       dpts::par::MetaStats& st) {
  using namespace dpts;
  std::vector<par::QemPieceMesh> outputs;
  const std::vector<core::Piece> pieces = par::plan_qem(source, qo, progress, st, &outputs);
  mpi::go(true);
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<std::size_t> own = mpi::share(pieces.size(), 0, mpi::ranks());
  // note: progress counts pieces, here and received, so it ends at 100 % of all of them.
  const double share = pieces.empty() ? 1.0 : static_cast<double>(own.size()) / pieces.size();
  std::size_t received = 0;
  try {
    par::simplify_qem_pieces(
        source, qo, pieces, own, st, outputs,
        [&](double f, std::string_view s) { return !progress || progress(f * share, s); });
  } catch (...) {
    // The other ranks are sending: take their pieces (dropped) before failing, so none waits.
    std::vector<par::QemPieceMesh> drop(pieces.size());
    mpi::receive(drop, st, nullptr);
    throw;
  }
  // note: a stop asked for meanwhile is honoured once every rank's pieces are in.
  const std::string failure = mpi::receive(outputs, st, [&] {
    ++received;
    if (progress) progress(share + static_cast<double>(received) / pieces.size(), "simplify");
  });
  if (g_cancel.load() != 0) throw dpts::Cancelled();  // every rank was told, and stopped
  if (!failure.empty()) throw dpts::InputError(failure);
  if (progress && !progress(1.0, "simplify")) throw dpts::Cancelled();
  st.simplify_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return par::merge_qem(source, qo, pieces, outputs, st, progress);
}
#endif

// Runs the method (api::simplify: every method, dpts-mpi's qem over its ranks) and writes its
// mesh: the output is claimed once the input is known to be valid, committed once written.
int simplify_and_write(const dpts::cli::ParOptions& o, dpts::cli::ProgressPrinter& printer,
                       const dpts::core::Progress& progress,
                       std::chrono::steady_clock::time_point start) {
  using namespace dpts;
  api::SimplifyRequest r;
  r.algo = o.algo;
  r.keep = o.keep;
  r.levels = o.levels;
  r.max_error = o.max_error;
  r.value_points = o.value_points;
  r.elimination = o.elimination;
  r.memory_limit_bytes = cli::memory_limit_bytes(o);
  r.spill = true;  // qem: the mesh goes to disk as it is made, not into memory
  const bool pieces = o.algo == par::Algorithm::qem || par::is_meta(o.algo);
  if (pieces) r.tile_bytes = piece_cache(o);
#ifdef DPTS_MPI
  r.qem_engine = simplify_qem_ranks;
#endif
  std::optional<io::AtomicOutputFile> out;
  // note: the input's notes (its CRS projected, scale and offset, bands) are printed once its
  // cells are counted: the piece engines learn only then that a band is all no-data, and a
  // refused input gets its one line alone.
  std::vector<std::string> notes;  // those not printed yet
  auto flush_notes = [&] {
    if (notes.empty()) return;
    printer.finish();
    print_notes(notes, o);
    notes.clear();
  };
  r.on_input = [&](const io::DemInfo& dem) {
    if (!g_report.path.empty()) g_report.input_json = cli::input_json(dem, 0, 0);
    notes = dem.notes;
    if (!o.format_note.empty()) notes.push_back(o.format_note);
    out.emplace(o.output);  // the input is valid: now claim the output (fails early)
  };
  const core::Progress noted = [&](double f, std::string_view stage) {
    if (stage != "count") flush_notes();
    return progress(f, stage);
  };
  api::Simplification result = api::simplify(open_input(o), o.input, r, noted);
  flush_notes();
  printer.finish();
  after_simplify(o, result);
  const std::size_t faces = result.face_count();
  const auto t_write = std::chrono::steady_clock::now();
  write_mesh(o, result.dem, result, *out);
  if (!g_report.path.empty() && pieces) g_report.pieces_json = cli::pieces_json(result.pieces);
  // A report written as a stream to a device or named pipe goes out before OUTPUT is put in
  // place: one that cannot be written (--report /dev/full) fails the run with OUTPUT
  // untouched. (A report file is written after, atomically, as a failed run's is; so is one
  // to standard output or error, after the summary line.)
  if (!g_report.path.empty() && io::AtomicOutputFile::streams_to(g_report.path) &&
      !io::AtomicOutputFile::names_descriptor(g_report.path) &&
      !io::AtomicOutputFile::streams_to(o.output)) {
    out->stream().flush();
    record_output(o, result.dem, result.valid_cells, result.input_vertices, result.kept_vertices,
                  faces, out->temp_path().string());
    const std::string failed = g_report.write(o, "ok", 0, "");
    if (!failed.empty()) throw IoError("report not written: " + failed);
    g_report.written = true;
  }
  out->commit();
  if (o.verbose && pieces) {
    std::fprintf(stderr, DPTS_PROG ": stages: write %.2f s\n",
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t_write).count());
  }
  if (!g_report.written) {
    record_output(o, result.dem, result.valid_cells, result.input_vertices, result.kept_vertices,
                  faces, o.output);
  }
  summary(o, result.input_vertices, result.kept_vertices, faces, start);
  return 0;
}

int run(const dpts::cli::ParOptions& o) {
  using namespace dpts;
  if (o.help || o.version) {
    if (o.help) {
#ifdef DPTS_MPI
      std::cout << "Usage: mpirun -q -np N dpts-mpi [OPTIONS] INPUT OUTPUT\n"
                   "dpts-par's default mode (qem) with its pieces spread over N MPI ranks: the "
                   "same options\n(not --algo other than qem, not --batch) and the same output, "
                   "written by rank 0.\nINPUT must be readable on every rank. dpts-par's help "
                   "follows.\n\n";
#endif
      std::cout << cli::par_help();
    } else {
      std::cout << DPTS_PROG " " << DPTS_VERSION << " (GDAL " << GDALVersionInfo("RELEASE_NAME")
                << ")\n";
    }
    std::cout.flush();
    if (!std::cout) throw IoError("cannot write to standard output");
    return 0;
  }
  const int threads = par::thread_count(o.threads);
  g_report.threads = threads;
  g_report.clock.enter("open");
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<std::size_t>(threads));
#ifdef DPTS_MPI
  if (o.algo != par::Algorithm::qem) {
    throw UsageError("--algo " + o.algo_text +
                     ": dpts-mpi runs the default qem engine only (dpts-par runs the others)");
  }
  if (o.input.rfind("/vsistdin", 0) == 0) {
    throw UsageError("INPUT -: dpts-mpi reads INPUT on every rank, standard input cannot be");
  }
#endif
  apply_config(o);
  if (o.output == "/dev/stdout" && cli::std_stream_was_closed(1)) {
    throw IoError("OUTPUT -: standard output is closed");
  }
  if (dpts::cli::same_file(o.input, o.output)) {
    throw UsageError(o.output + ": OUTPUT is the INPUT file; refusing to overwrite it");
  }
  // A report that cannot be written fails the run before any work (a probe, removed again;
  // not for a pipe or device, which opening would block or consume).
  if (!o.report.empty() && !io::AtomicOutputFile::streams_to(o.report)) {
    io::AtomicOutputFile probe(o.report);
  }
  const auto start = std::chrono::steady_clock::now();
  cli::ProgressPrinter printer(DPTS_PROG, o.quiet, &g_cancel);
  const core::Progress progress = [&](double f, std::string_view s) {
    g_report.clock.enter(s);
    return printer(f, s);
  };

  return simplify_and_write(o, printer, progress, start);
}

// This executable's path, for batch children.
std::string self_path(const char* argv0) {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(argv0) : p.string();
}

// What every process (and every rank of dpts-mpi) sets up first: signals, malloc and GDAL.
void start_process() {
  // note: sigaction without SA_RESTART, so a batch's waitpid() returns on a signal. A hang-up
  // (the terminal closed) stops the run as Ctrl-C does; a closed pipe on stderr does not
  // kill it (the write fails instead), so the temporary file is always removed. mpirun passes
  // a Ctrl-C on to every rank: each stops as rank 0 does.
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGHUP, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  dpts::par::keep_freed_memory();
  GDALAllRegister();
  // Every thread's: GDAL's errors become our one-line messages (a pushed handler is the
  // calling thread's only, and worker threads printed GDAL's own lines).
  CPLSetErrorHandler(CPLQuietErrorHandler);
  // A bounded block cache: GDAL's default (5 % of RAM) would cache the whole raster.
  g_user_cache = CPLGetConfigOption("GDAL_CACHEMAX", nullptr) != nullptr;
  if (!g_user_cache) CPLSetConfigOption("GDAL_CACHEMAX", "64");
}

#ifdef DPTS_MPI
// A rank other than 0: plans as rank 0 does, and once rank 0 gives the word simplifies its
// share of the pieces and sends them. Silent: rank 0 says what failed, here or there.
int run_rank(int argc, char** argv) {
  using namespace dpts;
  start_process();
  const core::Progress stop = [](double, std::string_view) { return g_cancel.load() == 0; };
  std::string error;
  std::optional<io::DemInfo> dem;
  std::optional<io::GdalRaster> source;
  std::optional<tbb::global_control> parallelism;
  std::vector<core::Piece> pieces;
  std::vector<par::QemPieceMesh> outputs;  // the pilot's pieces' among them
  par::MetaStats st;
  par::QemEngineOptions qo;
  bool planned = false;
  try {
    const cli::ParOptions o = cli::parse_par(std::vector<std::string>(argv + 1, argv + argc));
    if (!o.help && !o.version && o.batch.empty() && o.algo == par::Algorithm::qem) {
      parallelism.emplace(tbb::global_control::max_allowed_parallelism,
                          static_cast<std::size_t>(par::thread_count(o.threads)));
      apply_config(o);
      dem.emplace(io::open_dem(o.input, read_options(o)));
      source.emplace(*dem);
      qo = qem_options(o);
      pieces = par::plan_qem(*source, qo, stop, st, &outputs);
      planned = true;
    }
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!mpi::go(false)) return 0;  // rank 0 failed first, and says why
  try {
    if (!planned) throw std::runtime_error(error.empty() ? "could not plan the pieces" : error);
    const std::vector<std::size_t> own = mpi::share(pieces.size(), mpi::rank(), mpi::ranks());
    par::simplify_qem_pieces(*source, qo, pieces, own, st, outputs, stop);
    for (const std::size_t i : own) {
      mpi::send_piece(i, par::to_bytes(outputs[i], st.pieces[i]));
      outputs[i] = {};
    }
    mpi::send_end();
  } catch (const std::exception& e) {
    mpi::send_error(e.what());  // Cancelled's: "interrupted"
  }
  return 0;
}
#endif

int par_main(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
#ifdef DPTS_MPI
  dpts::mpi::init(argc, argv);
  int code = 0;
  if (dpts::mpi::rank() != 0) {
    code = run_rank(argc, argv);
  } else {
    code = par_main(argc, argv);
    if (!dpts::mpi::went()) dpts::mpi::go(false);  // failed before its word: the others stop
  }
  dpts::mpi::finalize();
  return code;
#else
  return par_main(argc, argv);
#endif
}

namespace {

int par_main(int argc, char** argv) {
  dpts::cli::reopen_closed_std_streams();
  start_process();
  const std::vector<std::string> args(argv + 1, argv + argc);
  dpts::cli::ParOptions o;
  auto report = [&](const std::string& status, int code, const std::string& error) {
    if (o.help || o.version || g_report.written) return code;
    const std::string failed = g_report.write(o, status, code, error);
    // A run that failed said why already; one that worked fails now.
    if (failed.empty() || code != 0) return code;
    std::cerr << DPTS_PROG ": error: report not written: " << failed << "\n";
    return 1;
  };
  try {
    o = dpts::cli::parse_par(args);
    g_report.path = o.report;
    g_report.args = args;
#ifdef DPTS_MPI
    if (!o.batch.empty())
      throw dpts::UsageError("--batch: not with dpts-mpi (dpts-par runs batches)");
#endif
    if (!o.batch.empty()) return dpts::cli::run_batch(o, self_path(argv[0]), &g_cancel);
    return report("ok", run(o), "");
  } catch (const dpts::UsageError& e) {
    // note: one line, the pointer to --help on it (bad input gets one line, usage too).
    std::cerr << DPTS_PROG ": " << dpts::cli::one_line(e.what()) << "; see " DPTS_PROG " --help\n";
    return report("failed", 2, e.what());
  } catch (const dpts::Cancelled&) {
    std::cerr << "\n" DPTS_PROG ": interrupted; no output written\n";
    return report("interrupted", 1, "interrupted by a signal; no output written");
  } catch (const std::bad_alloc&) {
    // note: the message is built from what is at hand; the memory asked for is not known.
    const std::string why =
        "out of memory in stage " + g_report.clock.stage() + " (peak " +
        std::to_string(dpts::par::peak_rss_kb() >> 10) +
        " MB); lower --tile-mb or --threads, or set --max-memory to be refused up front";
    std::cerr << DPTS_PROG ": error: " << why << "\n";
    return report("failed", 1, why);
  } catch (const std::exception& e) {
    std::cerr << DPTS_PROG ": error: " << dpts::cli::one_line(e.what()) << "\n";
    return report("failed", 1, e.what());
  }
}

}  // namespace

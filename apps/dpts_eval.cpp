// dpts-eval: how well does a TIN preserve the surface distances of the DEM it came from?
// Thin: parse flags, read the DEM and the mesh, call the evaluator, report.
#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "api/evaluation.hpp"
#include "apps/cli.hpp"
#include "core/errors.hpp"
#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/surface_sampling.hpp"
#include "io/atomic_output_file.hpp"
#include "io/dem_reader.hpp"
#include "io/json.hpp"
#include "io/pictures.hpp"
#include "io/sample_points.hpp"
#include "parallel/evaluate.hpp"
#include "parallel/memory.hpp"

namespace {

using dpts::UsageError;

// Set by SIGINT/SIGTERM while a --pairs-out file is being made: the run stops at the next
// progress call and the file's temporary is removed. A lock-free atomic (signal-safe).
std::atomic<int> g_cancel{0};
static_assert(std::atomic<int>::is_always_lock_free);
extern "C" void on_signal(int sig) {
  g_cancel.store(1, std::memory_order_relaxed);
  std::signal(sig, SIG_DFL);  // note: a second signal ends the process at once
}

struct Options {
  std::string dem, mesh, t_srs;
  int band = 1;
  std::string sample_points, pairs_out;  // --sample-points FILE.csv, --pairs-out FILE.csv
  std::string error_map, hillshade;      // --error-map, --hillshade-compare FILE.png
  bool edges = false;                    // --edges: the TIN's edges over its hillshade
  dpts::par::EvalOptions eval;
  double snap_m = -1;  // < 0: default
  int threads = 0;
  std::size_t max_memory_mb = 0;  // 0: what is available when the geodesics start
  bool json = false, quiet = false, help = false, version = false;
};

const char* kHelp = R"(usage: dpts-eval --dem DEM --mesh MESH [options]

Measures how well a TIN preserves the surface (geodesic) distances of the DEM it was made
from (the DPTS paper): for K random points uniform in the DEM's valid footprint, the error
is the mean over all pairs of |GD_T - GD_T'| / GD_T, where T is the DEM's full-resolution
grid TIN and T' the mesh. Geodesics are searched on the paper's Steiner graph (points every
delta along edges, each triangle's boundary points pairwise connected) with straight segments
across faces (each label keeps the point its segment starts from and the part of its edge that
point sees), each pair's two searches meeting in the middle (one way on a mesh with holes),
then each path is unfolded and pulled taut into an exact, locally shortest geodesic, and each
pair's route on either mesh is also pulled taut on the other (by turns, while either shortens),
the shorter kept: under 0.01 % above exact on average on real DEMs at the default delta, and
the measure within 1.4 % of the exact one (--steiner keeps the paper's Steiner distances,
0.7 % above).
The result is the mean over independent sets. Also reports the mesh's validity over
the DEM (orientation, coverage, faces over no-data, its boundary's length against the
footprint's outline: longer where a seam inside was left open) and its vertical error at
every valid cell centre.

  --dem DEM          the original DEM (any raster GDAL reads)
  --band B           the DEM's band holding the heights (default 1), as given to dpts-par
  --mesh MESH        the TIN, in the same CRS as dpts-par writes for DEM (see --t-srs): a
                     PLY with vertex x, y, z and triangle faces, an OBJ of triangles, an STL
                     (binary or ASCII), or a GeoPackage of one layer of triangles (Polygon Z,
                     Triangle Z, MultiPolygon Z, TIN Z)
  --points K         points per set (default 100)
  --sets S           independent sets (default 3)
  --seed N           seed of the sample points (default 1)
  --sample-points FILE.csv
                     measure these points instead of random ones: a header line exactly
                     set,x,y then one point a line (x, y in the mesh's CRS; point i of set s is
                     the i-th line of set s, both counted from 0; sets numbered 0 to S-1 without
                     gaps, each with the same number of points, at least 2); gives K and S, so
                     --points, --sets and --seed are refused with it
  --pairs-out FILE.csv
                     write set,i,j,gd_T,gd_S,rel_err for every pair i < j of every set (sets
                     from 0; gd inf where not connected, rel_err empty where not measured);
                     the file appears only when the run succeeds
  --error-map FILE.png
                     draw the vertical error (mesh minus DEM) at every valid cell: blue below,
                     red above, saturating near the 99th percentile, with a colour bar, a scale
                     bar, the RMSE and the maximum (at most 1000 pixels a side: each pixel
                     shows its block's largest error)
  --hillshade-compare FILE.png
                     draw the hillshades of the DEM and of the mesh side by side
  --edges            with --hillshade-compare: draw the mesh's edges over its hillshade
  --exact            exact geodesics (CGAL's Surface_mesh_shortest_path, Xin-Wang) instead of
                     the Steiner graph: a reference for small DEMs only, each source costing
                     about 0.75 s and 250 MB on a 100 x 100 grid, one per thread at once (not
                     bounded: --max-memory and --delta are refused with it); the mesh must be a
                     manifold surface with consistent orientation (no folded faces)
  --steiner          the paper's Steiner distances, not straightened (faster, but 0.7 %
                     long on average at the default delta, a bias as large as the error
                     measured on good meshes)
  --delta D          Steiner spacing in metres on both meshes (default: 0.5 x the mean edge
                     length of T, and 0.35 x that of the mesh but not less than T's; with
                     --steiner 0.25 x that of T on both); smaller finds the shortest route in
                     more near ties, at more cost
  --snap M           points outside the mesh by at most M metres are moved onto it
                     (default 0, or half a cell when the DEM is reprojected)
  --t-srs CRS        the mesh's CRS when dpts-par was given --t-srs
  --threads N        worker threads (default: all cores)
  --max-memory MB    memory the run may use (default: what is available when the geodesics
                     start); each search needs 36 bytes per Steiner node (12 with --steiner),
                     so fewer threads search at once when all do not fit; where two do not,
                     the pairs are searched one way (about twice the time); a run that does
                     not fit with one is refused before the graphs are built; the pairs'
                     arrays (8 x (6 x S + 10) bytes a pair) count too, and their routes kept
                     for the other mesh past 8 MB (or the memory left) go to an unnamed file
                     in TMPDIR (else /tmp)
  --json             print one JSON object with all figures as the last line
  --quiet            only the JSON line (or nothing but errors)
  --help, --version
A mesh given as a triangle soup (each face with its own corners, as STL and GeoPackage hold
it) is welded first: vertices at identical x, y, z are merged (reported). The run fails
(exit 1, one line) when sample points lie outside the mesh (or, given, outside the DEM), when
pairs connected on T are not on the mesh (a mesh in parts or slit: their count), or when an
output cannot be written. Pairs not connected on T (islands of valid cells) cannot be
measured: they are left out and counted.
Exit status: 0 ok, 1 failure (bad input, points outside the mesh, a failed write), 2 bad usage.
)";

Options parse(const std::vector<std::string>& args) {
  Options o;
  // Flags given explicitly, for the combinations refused.
  std::vector<std::string> given;
  dpts::cli::ArgReader in(args);
  while (in.next()) {
    const std::string a = in.arg();
    if (!in.is_flag()) throw UsageError(a + ": unexpected argument");
    auto value = [&] { return in.value(); };
    if (a.rfind("--", 0) == 0) given.push_back(a);
    if (a == "--help" || a == "-h") {
      o.help = true;
    } else if (a == "--version") {
      o.version = true;
    } else if (a == "--dem") {
      o.dem = value();
    } else if (a == "--mesh") {
      o.mesh = value();
    } else if (a == "--points") {
      o.eval.points = dpts::cli::parse_number<int>(a, value(), 2, "an integer >= 2");
    } else if (a == "--sets") {
      o.eval.sets = dpts::cli::parse_number<int>(a, value(), 1, "an integer >= 1");
    } else if (a == "--seed") {
      o.eval.seed = dpts::cli::parse_number<std::uint64_t>(a, value(), 0, "a non-negative integer");
    } else if (a == "--delta") {
      o.eval.delta_m = dpts::cli::parse_number<double>(a, value(), 1e-9, "a length in metres > 0");
    } else if (a == "--snap") {
      o.snap_m = dpts::cli::parse_number<double>(a, value(), 0.0, "a length in metres >= 0");
    } else if (a == "--t-srs") {
      o.t_srs = value();
    } else if (a == "--band") {
      o.band = dpts::cli::parse_number<int>(a, value(), 1, "an integer >= 1");
    } else if (a == "--threads") {
      o.threads = dpts::cli::parse_number<int>(a, value(), 1, "an integer >= 1");
    } else if (a == "--max-memory") {
      o.max_memory_mb = dpts::cli::parse_number<std::size_t>(a, value(), 1, "an integer >= 1 (MB)");
    } else if (a == "--sample-points") {
      o.sample_points = value();
    } else if (a == "--pairs-out") {
      o.pairs_out = value();
    } else if (a == "--error-map") {
      o.error_map = value();
    } else if (a == "--hillshade-compare") {
      o.hillshade = value();
    } else if (a == "--edges") {
      o.edges = true;
    } else if (a == "--exact") {
      o.eval.exact = true;
    } else if (a == "--steiner") {
      o.eval.straighten = false;
    } else if (a == "--json") {
      o.json = true;
    } else if (a == "--quiet" || a == "-q") {
      o.quiet = true;
    } else {
      throw UsageError(a + ": unknown option");
    }
  }
  if (!o.help && !o.version && (o.dem.empty() || o.mesh.empty())) {
    throw UsageError("expected --dem DEM and --mesh MESH");
  }
  auto has = [&](const char* flag) {
    return std::find(given.begin(), given.end(), flag) != given.end();
  };
  auto refuse = [&](const char* a, const char* b, const char* why) {
    if (has(a) && has(b))
      throw UsageError(std::string(a) + " and " + b + " cannot be combined (" + why + ")");
  };
  for (const char* flag : {"--points", "--sets", "--seed"}) {
    refuse("--sample-points", flag, "the file gives the points and sets");
  }
  refuse("--exact", "--delta", "exact geodesics have no Steiner spacing");
  refuse("--exact", "--steiner", "one kind of geodesics at a time");
  refuse("--exact", "--max-memory", "the memory of exact geodesics is not bounded");
  if (o.edges && o.hillshade.empty()) throw UsageError("--edges: needs --hillshade-compare");
  const std::pair<const char*, const std::string*> outputs[] = {
      {"--pairs-out", &o.pairs_out},
      {"--error-map", &o.error_map},
      {"--hillshade-compare", &o.hillshade}};
  for (const auto& [flag, path] : outputs) {
    if (path->empty()) continue;
    for (const std::string* input : {&o.dem, &o.mesh, &o.sample_points}) {
      if (!input->empty() && dpts::cli::same_file(*path, *input)) {
        throw UsageError(std::string(flag) + " " + *path + ": is an input of the run");
      }
    }
  }
  // Two outputs in one file: the later would replace the earlier.
  for (std::size_t i = 0; i < std::size(outputs); ++i) {
    for (std::size_t j = i + 1; j < std::size(outputs); ++j) {
      if (outputs[i].second->empty() || outputs[j].second->empty() ||
          !dpts::cli::same_file(*outputs[i].second, *outputs[j].second)) {
        continue;
      }
      throw UsageError(std::string(outputs[i].first) + " and " + outputs[j].first +
                       ": the same file");
    }
  }
  return o;
}

// Standard output after everything is printed: a failed write (a full disk) is an error.
void check_stdout() {
  errno = 0;
  std::cout.flush();
  if (std::fflush(stdout) != 0 || std::ferror(stdout) || !std::cout) {
    const int err = errno;
    throw dpts::IoError(std::string("standard output: write failed") +
                        (err ? std::string(" (") + std::strerror(err) + ")" : std::string()));
  }
}

// --pairs-out: a file appears only complete (AtomicOutputFile: nothing when the run fails); a
// device or pipe that exists (/dev/stdout) is written to directly, its writes checked.
class PairsOutput {
 public:
  explicit PairsOutput(const std::string& path) : path_(path) {
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (std::filesystem::is_directory(st)) throw dpts::IoError(path + ": is a directory");
    if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)) {
      device_.open(path, std::ios::binary);
      if (!device_) throw dpts::IoError(path + ": cannot open for writing");
    } else {
      file_.emplace(path);
    }
  }
  // Writes the records: into the file (which commit() puts in place), or to the device at once.
  void write(const std::vector<dpts::io::PairRecord>& records) {
    if (file_) return dpts::io::write_pair_records(file_->stream(), records);
    errno = 0;
    dpts::io::write_pair_records(device_, records);
    device_.flush();
    if (!device_) {
      const int err = errno;
      throw dpts::IoError(path_ + ": write failed" +
                          (err ? std::string(" (") + std::strerror(err) + ")" : std::string()));
    }
  }
  void commit() {
    if (file_) file_->commit();
  }

 private:
  std::string path_;
  std::optional<dpts::io::AtomicOutputFile> file_;
  std::ofstream device_;
};

// The unique edges of a mesh's faces, each as grid positions c0, r0, c1, r1.
std::vector<std::array<double, 4>> grid_edges(
    const std::vector<double>& grid_xy, const std::vector<std::array<std::uint32_t, 3>>& faces) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  pairs.reserve(3 * faces.size());
  for (const auto& f : faces) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = f[static_cast<std::size_t>(k)],
                          b = f[static_cast<std::size_t>((k + 1) % 3)];
      pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  std::vector<std::array<double, 4>> edges;
  edges.reserve(pairs.size());
  for (const auto& [a, b] : pairs) {
    edges.push_back({grid_xy[2 * a], grid_xy[2 * a + 1], grid_xy[2 * b], grid_xy[2 * b + 1]});
  }
  return edges;
}

struct Pictures {
  std::string error_map, hillshade;  // PNG bytes (empty: not asked for)
};

// The mesh's height at every valid cell centre of the DEM (located as the vertical error is),
// then the pictures asked for.
Pictures draw_pictures(const dpts::io::Dem& dem, const dpts::core::PointLocator& locate,
                       double snap, bool error_map, bool hillshade, std::size_t mesh_vertices,
                       const std::vector<std::array<double, 4>>& edges) {
  using namespace dpts;
  const auto& g = dem.grid;
  std::vector<std::uint32_t> cells;
  for (std::size_t i = 0; i < g.z.size(); ++i) {
    if (!std::isnan(g.z[i])) cells.push_back(static_cast<std::uint32_t>(i));
  }
  const std::vector<double> xy = dem.output_xy(cells);
  const float none = std::numeric_limits<float>::quiet_NaN();
  io::CellRaster heights, mesh;
  heights.width = mesh.width = g.width;
  heights.height = mesh.height = g.height;
  heights.cell_x_m = mesh.cell_x_m = dem.frame.col_metres();
  heights.cell_y_m = mesh.cell_y_m = dem.frame.row_metres();
  heights.values.assign(g.z.size(), none);
  mesh.values.assign(g.z.size(), none);
  tbb::parallel_for(std::size_t{0}, cells.size(), [&](std::size_t i) {
    const std::uint32_t c = cells[i];
    heights.values[c] = static_cast<float>(g.z[c]);
    if (const auto hit = locate.locate(xy[2 * i], xy[2 * i + 1], snap)) {
      mesh.values[c] = static_cast<float>(hit->point.z);
    }
  });
  Pictures p;
  if (hillshade) {
    p.hillshade = io::hillshade_compare_png(
        heights, mesh, "TIN (" + std::to_string(mesh_vertices) + " VERTICES)", edges);
  }
  if (error_map) {
    io::CellRaster error = mesh;
    for (std::size_t i = 0; i < error.values.size(); ++i) {
      error.values[i] = mesh.values[i] - heights.values[i];  // NaN where either is none
    }
    p.error_map = io::error_map_png(error);
  }
  return p;
}

// The text report on stdout (what --quiet leaves out).
void print_report(const Options& o, const dpts::api::Evaluation& ev, double secs) {
  using namespace dpts;
  const core::TriMesh& t = ev.t;
  const core::TriMesh& s = ev.s;
  const par::EvalResult& r = ev.result;
  const par::EvalOptions& eo = ev.options;
  const bool given = !eo.sample_xy.empty();
  std::printf("dem              %s: %zu vertices, %zu faces (grid TIN)\n", o.dem.c_str(),
              t.vertex_count(), t.faces.size());
  std::printf("mesh             %s: %zu vertices, %zu faces\n", o.mesh.c_str(), s.vertex_count(),
              s.faces.size());
  if (ev.merged > 0) {
    std::printf("welded           %zu vertices at the position of an earlier one merged into it\n",
                ev.merged);
  }
  std::printf(
      "validity         %zu faces not counter-clockwise, %zu bad edges, %zu faces over no-data\n",
      ev.validity.clockwise_or_flat, ev.validity.bad_edges, ev.over_nodata);
  std::printf(
      "coverage         mesh area / footprint area = %.9f; mesh boundary / footprint outline = "
      "%.6f%s\n",
      ev.validity.area / ev.footprint_area, ev.validity.boundary_length / ev.footprint_outline,
      ev.validity.boundary_length > 1.001 * ev.footprint_outline
          ? " (longer: a crack or slit inside, or a moved outline)"
          : "");
  std::printf(
      "vertical error   RMSE %.4f m, max %.4f m over %zu cell centres (%zu outside the mesh)\n",
      ev.rmse, ev.vmax, ev.measured, ev.uncovered);
  if (r.exact) {
    std::printf("geodesics        exact (CGAL Surface_mesh_shortest_path): T %.2f s, T' %.2f s\n",
                r.original_s, r.simplified_s);
  } else {
    std::printf(
        "steiner graphs   T delta %.4f m, %zu nodes (%.2f s); T' delta %.4f m, %zu nodes "
        "(%.2f s)\n",
        r.delta_m, r.original_nodes, r.original_s, r.delta_mesh_m, r.simplified_nodes,
        r.simplified_s);
    if (eo.straighten) {
      std::printf(
          "geodesics        Steiner paths straightened: %zu paths (%zu could not be, their "
          "Steiner length kept); %zu distances shortened along the other mesh's routes\n",
          r.straightened, r.straighten_failed, r.shortened);
    } else {
      std::printf("geodesics        Steiner distances (the paper's; not straightened)\n");
    }
    const std::string bound =
        r.max_searches ? "at most " + std::to_string(r.max_searches) + " searches at once"
                       : "no bound on searches";
    const std::string routes =
        r.routes_bytes ? ", routes " + par::format_bytes(static_cast<double>(r.routes_bytes)) : "";
    std::printf("memory           the larger graph about %s, a search %s, the pairs %s%s (%s)\n",
                par::format_bytes(static_cast<double>(r.graphs_bytes)).c_str(),
                par::format_bytes(static_cast<double>(r.search_bytes)).c_str(),
                par::format_bytes(static_cast<double>(r.pairs_bytes)).c_str(), routes.c_str(),
                bound.c_str());
    std::printf(
        "searched         %.1f %% of T, %.1f %% of T' per query on average (pairs measured one "
        "way: %zu on T, %zu on T')\n",
        100 * r.original_searched, 100 * r.simplified_searched, r.original_one_way,
        r.simplified_one_way);
  }
  std::printf(
      "pairs            %zu measured; left out: %zu not connected on T, %zu at distance 0\n",
      r.pairs_measured, r.pairs_unconnected, r.pairs_coincident);
  for (std::size_t i = 0; i < r.set_errors.size(); ++i) {
    // note: given sets keep the numbers of their file (from 0)
    std::printf("distance error   %sset %zu: %.6f\n", given ? "sample " : "", given ? i : i + 1,
                r.set_errors[i]);
  }
  std::printf("distance error   %.6f (mean of %d sets of %d points%s; %zu points snapped)\n",
              r.distance_error, eo.sets, eo.points,
              given ? (" from " + o.sample_points).c_str() : "", r.snapped);
  std::printf("time             %.2f s\n", secs);
}

// Progress on stderr once the run has lasted a second (not when quiet): a line as each stage
// starts, and within a long geodesic stage one per tenth of its sources searched, at most every
// kProgressEvery seconds. Returns false (stop) once a signal asked for it.
dpts::core::Progress progress_lines(bool quiet, std::chrono::steady_clock::time_point start) {
  constexpr double kProgressEvery = 10;
  struct Last {
    double line = 0;
    int tenth = 0;
  };
  auto last = std::make_shared<Last>();
  return [quiet, start, last](double fraction, std::string_view stage) {
    const std::string what(stage);
    if (g_cancel.load(std::memory_order_relaxed) != 0) return false;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (quiet || elapsed < 1.0) return true;
    const int tenth = static_cast<int>(fraction * 10);
    if (fraction == 0) {
      std::fprintf(stderr, "dpts-eval: %s (%.0f s)\n", what.c_str(), elapsed);
    } else if (tenth > last->tenth && tenth < 10 && elapsed - last->line >= kProgressEvery) {
      std::fprintf(stderr, "dpts-eval: %s: %d %% of the sources searched (%.0f s)\n", what.c_str(),
                   10 * tenth, elapsed);
    } else {
      return true;
    }
    last->line = elapsed;
    last->tenth = tenth;
    return true;
  };
}

int run(const Options& o) {
  using namespace dpts;
  if (o.help) {
    std::cout << kHelp;
    check_stdout();
    return 0;
  }
  if (o.version) {
    std::cout << "dpts-eval " << DPTS_VERSION << "\n";
    check_stdout();
    return 0;
  }
  const auto start = std::chrono::steady_clock::now();
  const int threads = dpts::par::thread_count(o.threads);
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<std::size_t>(threads));
  api::EvalRequest request;
  request.dem = o.dem;
  request.mesh = o.mesh;
  request.t_srs = o.t_srs;
  request.band = o.band;
  request.sample_points = o.sample_points;
  request.eval = o.eval;
  request.snap_m = o.snap_m;
  request.max_memory_mb = o.max_memory_mb;
  std::optional<io::AtomicOutputFile> error_map_out, hillshade_out;
  // Which band of several is measured, as dpts-par says which it simplified: said once the
  // measure is made (a failure before is its one line alone).
  // So are the DEM's warnings (heights read as no-data, usual no-data values read as heights):
  // a measure against voids read as pits is no measure of the TIN.
  std::vector<std::string> dem_notes;
  const std::unique_ptr<api::Evaluation> ev = api::load(request, [&](const io::Dem& dem) {
    if (!dem.bands_note.empty()) dem_notes.push_back(dem.bands_note);
    dem_notes.insert(dem_notes.end(), dem.height_warnings.begin(), dem.height_warnings.end());
    // Nor may an output overwrite any file of the DEM's dataset (an ENVI .hdr, a VRT's
    // source, the zip behind /vsizip/).
    for (const auto& [flag, path] :
         {std::pair<const char*, const std::string*>{"--pairs-out", &o.pairs_out},
          {"--error-map", &o.error_map},
          {"--hillshade-compare", &o.hillshade}}) {
      if (const std::string* f =
              path->empty() ? nullptr : dpts::cli::same_file_in(*path, dem.files)) {
        throw UsageError(std::string(flag) + " " + *path + ": is " + *f + ", a file of the DEM");
      }
    }
    // The pictures' files are claimed now (a folder that does not exist fails before any
    // work); they appear only when the run succeeds.
    if (!o.error_map.empty()) error_map_out.emplace(o.error_map);
    if (!o.hillshade.empty()) hillshade_out.emplace(o.hillshade);
  });
  const io::Dem& dem = ev->dem;
  const core::TriMesh& s = ev->s;
  // The pictures, drawn now (their rasters freed before the geodesics) and written at the end.
  std::string error_map_png, hillshade_png;
  if (error_map_out || hillshade_out) {
    std::vector<std::array<double, 4>> edges;
    if (o.edges) edges = grid_edges(dem.grid_xy(core::xy_of(s.xyz)), s.faces);
    const Pictures p = draw_pictures(dem, *ev->locate_s, ev->snap, error_map_out.has_value(),
                                     hillshade_out.has_value(), s.vertex_count(), edges);
    error_map_png = p.error_map;
    hillshade_png = p.hillshade;
  }

  const core::Progress progress = progress_lines(o.quiet, start);
  // The pairs' file is opened (created beside its path) before the long part: a folder that
  // does not exist fails now, not after the geodesics.
  std::optional<PairsOutput> pairs_out;
  if (!o.pairs_out.empty()) {
    // note: only while a file is made is Ctrl-C caught (to remove it); otherwise it simply ends
    // the process, which writes nothing else.
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    pairs_out.emplace(o.pairs_out);
    ev->options.keep_pairs = true;
  }
  api::measure(*ev, request, progress);
  if (!o.quiet)
    for (const std::string& note : dem_notes) std::cerr << "dpts-eval: " << note << "\n";
  const par::EvalResult& r = ev->result;
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (pairs_out) {
    std::vector<io::PairRecord> records;
    records.reserve(r.pairs.size());
    for (const auto& p : r.pairs) records.push_back({p.set, p.i, p.j, p.on_t, p.on_s});
    pairs_out->write(records);
  }

  if (!o.quiet) print_report(o, *ev, secs);
  if (o.json) std::cout << ev->json(request, threads, secs) << "\n";
  // note: stdout first: a run whose report cannot be written fails, and leaves no pairs file.
  check_stdout();
  if (pairs_out) pairs_out->commit();
  auto put = [](std::optional<io::AtomicOutputFile>& out, const std::string& png) {
    if (!out) return;
    out->stream().write(png.data(), static_cast<std::streamsize>(png.size()));
    out->commit();
  };
  put(error_map_out, error_map_png);
  put(hillshade_out, hillshade_png);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  dpts::cli::reopen_closed_std_streams();
  GDALAllRegister();
  // Every thread's: GDAL's errors become our one-line messages (a pushed handler is the
  // calling thread's only, and worker threads printed GDAL's own lines).
  CPLSetErrorHandler(CPLQuietErrorHandler);
  if (!CPLGetConfigOption("GDAL_CACHEMAX", nullptr)) CPLSetConfigOption("GDAL_CACHEMAX", "64");
  try {
    return run(parse(std::vector<std::string>(argv + 1, argv + argc)));
  } catch (const dpts::UsageError& e) {
    std::cerr << "dpts-eval: " << dpts::cli::one_line(e.what()) << "; see dpts-eval --help\n";
    return 2;
  } catch (const dpts::Cancelled&) {
    std::cerr << "dpts-eval: interrupted; no output written\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "dpts-eval: error: out of memory (peak " << (dpts::par::peak_rss_kb() >> 10)
              << " MB); fewer --points or --threads, or set --max-memory\n";
    return 1;

  } catch (const std::exception& e) {
    std::cerr << "dpts-eval: error: " << dpts::cli::one_line(e.what()) << "\n";
    return 1;
  }
}

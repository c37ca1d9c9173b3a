// dpts-eval: how well does a TIN preserve the surface distances of the DEM it came from?
// Thin: parse flags, read the DEM and the mesh, call the evaluator, report.
#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "apps/cli.hpp"
#include "core/errors.hpp"
#include "core/footprint.hpp"
#include "core/mesh_check.hpp"
#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"
#include "io/json.hpp"
#include "io/ply.hpp"
#include "parallel/evaluate.hpp"
#include "parallel/meta.hpp"

namespace {

using dpts::UsageError;

struct Options {
  std::string dem, mesh, t_srs;
  dpts::par::EvalOptions eval;
  double snap_m = -1;  // < 0: default
  int threads = 0;
  std::size_t max_memory_mb = 0;  // 0: what is available when the geodesics start
  bool json = false, quiet = false, help = false, version = false;
};

const char* kHelp = R"(usage: dpts-eval --dem DEM --mesh MESH.ply [options]

Measures how well a TIN preserves the surface (geodesic) distances of the DEM it was made
from (the DPTS paper): for K random points uniform in the DEM's valid footprint, the error
is the mean over all pairs of |GD_T - GD_T'| / GD_T, where T is the DEM's full-resolution
grid TIN and T' the mesh, and geodesics are shortest paths on the Steiner graph (points every
delta along edges, each triangle's boundary points pairwise connected). The result is the
mean over independent sets. Also reports the mesh's validity over the DEM (orientation,
coverage, faces over no-data) and its vertical error at every valid cell centre.

  --dem DEM          the original DEM (any raster GDAL reads; band 1)
  --mesh MESH.ply    the TIN: any PLY with vertex x, y, z and triangle faces, in the same
                     CRS as dpts-par writes for DEM (see --t-srs)
  --points K         points per set (default 100)
  --sets S           independent sets (default 3)
  --seed N           seed of the sample points (default 1)
  --delta D          Steiner spacing in metres (default: 0.25 x the mean edge length of T,
                     which keeps Steiner distances within 1 % of exact geodesics on average)
  --snap M           points outside the mesh by at most M metres are moved onto it
                     (default 0, or half a cell when the DEM is reprojected)
  --t-srs CRS        the mesh's CRS when dpts-par was given --t-srs
  --threads N        worker threads (default: all cores)
  --max-memory MB    memory the run may use (default: what is available when the geodesics
                     start); each search needs 16 bytes per Steiner node, so fewer threads
                     search at once when all do not fit, and a run that does not fit with one
                     is refused before the graphs are built
  --json             print one JSON object with all figures as the last line
  --quiet            only the JSON line (or nothing but errors)
  --help, --version
Exit status: 0 ok, 1 failure (bad input, points outside the mesh), 2 bad usage.
)";

Options parse(const std::vector<std::string>& args) {
  Options o;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw UsageError(a + ": missing value");
      return args[++i];
    };
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
    } else if (a == "--threads") {
      o.threads = dpts::cli::parse_number<int>(a, value(), 1, "an integer >= 1");
    } else if (a == "--max-memory") {
      o.max_memory_mb = dpts::cli::parse_number<std::size_t>(a, value(), 1, "an integer >= 1 (MB)");
    } else if (a == "--json") {
      o.json = true;
    } else if (a == "--quiet" || a == "-q") {
      o.quiet = true;
    } else {
      throw UsageError(a + (a.rfind("-", 0) == 0 ? ": unknown option" : ": unexpected argument"));
    }
  }
  if (!o.help && !o.version && (o.dem.empty() || o.mesh.empty())) {
    throw UsageError("expected --dem DEM and --mesh MESH.ply");
  }
  return o;
}

int run(const Options& o) {
  using namespace dpts;
  if (o.help) {
    std::cout << kHelp;
    return 0;
  }
  if (o.version) {
    std::cout << "dpts-eval " << DPTS_VERSION << "\n";
    return 0;
  }
  const auto start = std::chrono::steady_clock::now();
  const int threads = o.threads > 0 ? o.threads : tbb::info::default_concurrency();
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                  static_cast<std::size_t>(threads));
  const io::Dem dem = io::read_dem(o.dem, io::DemReadOptions{o.t_srs}, nullptr);

  // T: the DEM's full-resolution grid TIN, in the output CRS dpts-par uses.
  const core::TriMesh t = dem.grid_mesh();
  // T': the mesh.
  io::Mesh ply = io::read_ply_file(o.mesh);
  io::check_triangles(ply, o.mesh);
  // A mesh of this DEM lies on its footprint; one far outside it is another DEM's, or in
  // another CRS (and its Steiner graph could be unboundedly large).
  {
    double lo[2] = {t.xyz[0], t.xyz[1]}, hi[2] = {t.xyz[0], t.xyz[1]};
    for (std::size_t v = 0; v < t.vertex_count(); ++v) {
      for (int k = 0; k < 2; ++k) {
        lo[k] = std::min(lo[k], t.xyz[3 * v + k]);
        hi[k] = std::max(hi[k], t.xyz[3 * v + k]);
      }
    }
    const double margin = 0.01 * std::hypot(hi[0] - lo[0], hi[1] - lo[1]);
    for (std::size_t v = 0; v < ply.vertex_count(); ++v) {
      const double x = ply.xyz[3 * v], y = ply.xyz[3 * v + 1];
      if (x < lo[0] - margin || x > hi[0] + margin || y < lo[1] - margin || y > hi[1] + margin) {
        throw InputError(o.mesh + ": vertex " + std::to_string(v) + " (" + std::to_string(x) +
                         ", " + std::to_string(y) + ") lies outside " + o.dem +
                         "; is the mesh of another DEM or in another CRS?");
      }
    }
  }
  core::TriMesh s{std::move(ply.xyz), std::move(ply.faces)};

  // Validity of T' over the DEM.
  const std::vector<double> s_xy = core::xy_of(s.xyz);
  const core::MeshCheck mc = core::check_mesh(s_xy, s.faces);
  const double footprint_area = core::mesh_area(core::xy_of(t.xyz), t.faces);
  const double tol = dem.to_output ? 0.01 : 1e-6;  // cells; reprojection rounding
  const std::size_t over_nodata =
      core::faces_over_nodata(dem.grid, dem.grid_xy(s_xy), s.faces, tol);

  // Vertical error at every cell centre of T's footprint.
  const core::PointLocator locate_s(s);
  const double snap =
      o.snap_m >= 0 ? o.snap_m : (dem.to_output ? 0.5 * dem.frame.metres_per_unit : 0.0);
  double sq = 0, vmax = 0;
  std::size_t measured = 0, uncovered = 0;
  for (std::size_t v = 0; v < t.vertex_count(); ++v) {
    const auto hit = locate_s.locate(t.xyz[3 * v], t.xyz[3 * v + 1], snap);
    if (!hit) {
      ++uncovered;
      continue;
    }
    const double dz = hit->point.z - t.xyz[3 * v + 2];
    sq += dz * dz;
    vmax = std::max(vmax, std::fabs(dz));
    ++measured;
  }

  par::EvalOptions eo = o.eval;
  eo.snap_m = snap;
  // What the geodesics may use: the limit less what the run holds already, or what is free.
  if (o.max_memory_mb > 0) {
    const std::size_t limit = o.max_memory_mb << 20, held = par::rss_kb() << 10;
    if (limit <= held) {
      throw InputError("--max-memory " + std::to_string(o.max_memory_mb) + ": the run holds " +
                       par::format_bytes(static_cast<double>(held)) +
                       " (DEM and meshes) before its geodesics start");
    }
    eo.memory_budget_bytes = limit - held;
  } else {
    eo.memory_budget_bytes = par::available_memory_bytes();
  }
  // Progress on stderr once the run has lasted a second (not with --quiet): a line as each
  // stage starts, and within a long geodesic stage one per tenth of its sources searched, at
  // most every kProgressEvery seconds.
  constexpr double kProgressEvery = 10;
  double last_line = 0;
  int last_tenth = 0;
  const par::StageProgress progress = [&](const std::string& what, double fraction) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (o.quiet || elapsed < 1.0) return true;
    const int tenth = static_cast<int>(fraction * 10);
    if (fraction == 0) {
      std::fprintf(stderr, "dpts-eval: %s (%.0f s)\n", what.c_str(), elapsed);
    } else if (tenth > last_tenth && tenth < 10 && elapsed - last_line >= kProgressEvery) {
      std::fprintf(stderr, "dpts-eval: %s: %d %% of the sources searched (%.0f s)\n", what.c_str(),
                   10 * tenth, elapsed);
    } else {
      return true;
    }
    last_line = elapsed;
    last_tenth = tenth;
    return true;  // note: dpts-eval writes no file, so Ctrl-C may simply end the process
  };
  par::EvalResult r;
  try {
    r = par::evaluate_distances(t, s, eo, progress);
  } catch (const std::invalid_argument& e) {  // the mesh's structure (see SteinerGraph)
    throw InputError(o.mesh + ": " + e.what());
  }
  const double secs =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rmse = measured ? std::sqrt(sq / measured) : 0.0;

  if (!o.quiet) {
    std::printf("dem              %s: %zu vertices, %zu faces (grid TIN)\n", o.dem.c_str(),
                t.vertex_count(), t.faces.size());
    std::printf("mesh             %s: %zu vertices, %zu faces\n", o.mesh.c_str(), s.vertex_count(),
                s.faces.size());
    std::printf(
        "validity         %zu faces not counter-clockwise, %zu bad edges, %zu faces over no-data\n",
        mc.clockwise_or_flat, mc.bad_edges, over_nodata);
    std::printf("coverage         mesh area / footprint area = %.9f\n", mc.area / footprint_area);
    std::printf(
        "vertical error   RMSE %.4f m, max %.4f m over %zu cell centres (%zu outside the mesh)\n",
        rmse, vmax, measured, uncovered);
    std::printf("steiner graphs   delta %.4f m: T %zu nodes (%.2f s), T' %zu nodes (%.2f s)\n",
                r.delta_m, r.original_nodes, r.original_s, r.simplified_nodes, r.simplified_s);
    const std::string bound =
        r.max_searches ? "at most " + std::to_string(r.max_searches) + " searches at once"
                       : "no bound on searches";
    std::printf("memory           graphs about %s, a search %s (%s)\n",
                par::format_bytes(static_cast<double>(r.graphs_bytes)).c_str(),
                par::format_bytes(static_cast<double>(r.search_bytes)).c_str(), bound.c_str());
    std::printf(
        "searched         %.1f %% of T, %.1f %% of T' per query on average (pairs measured one "
        "way: %zu on T, %zu on T')\n",
        100 * r.original_searched, 100 * r.simplified_searched, r.original_one_way,
        r.simplified_one_way);
    for (std::size_t i = 0; i < r.set_errors.size(); ++i) {
      std::printf("distance error   set %zu: %.6f\n", i + 1, r.set_errors[i]);
    }
    std::printf("distance error   %.6f (mean of %d sets of %d points; %zu points snapped)\n",
                r.distance_error, eo.sets, eo.points, r.snapped);
    std::printf("time             %.2f s\n", secs);
  }
  if (o.json) {
    io::JsonArray sets;
    for (double e : r.set_errors) sets.raw(io::json_number(e));
    std::cout << io::JsonObject()
                     .add("distance_error", r.distance_error)
                     .raw("distance_error_sets", sets.str())
                     .add("vertical_rmse", rmse)
                     .add("vertical_max", vmax)
                     .add("mesh_vertices", s.vertex_count())
                     .add("mesh_faces", s.faces.size())
                     .add("dem_vertices", t.vertex_count())
                     .add("dem_faces", t.faces.size())
                     .add("points", eo.points)
                     .add("sets", eo.sets)
                     .add("seed", static_cast<unsigned long long>(eo.seed))
                     .add("delta_m", r.delta_m)
                     .add("steiner_nodes_dem", r.original_nodes)
                     .add("steiner_nodes_mesh", r.simplified_nodes)
                     .add("searched_share_dem", r.original_searched)
                     .add("searched_share_mesh", r.simplified_searched)
                     .add("one_way_pairs_dem", r.original_one_way)
                     .add("one_way_pairs_mesh", r.simplified_one_way)
                     .add("snapped_points", r.snapped)
                     .add("memory_graphs_bytes", r.graphs_bytes)
                     .add("memory_search_bytes", r.search_bytes)
                     .add("max_searches", r.max_searches)
                     .add("faces_not_ccw", mc.clockwise_or_flat)
                     .add("bad_edges", mc.bad_edges)
                     .add("faces_over_nodata", over_nodata)
                     .add("coverage", mc.area / footprint_area)
                     .add("cells_outside_mesh", uncovered)
                     .add("threads", threads)
                     .add("dem", o.dem)
                     .add("mesh", o.mesh)
                     .add("seconds_geodesics_dem", r.original_s)
                     .add("seconds_geodesics_mesh", r.simplified_s)
                     .add("seconds", secs)
                     .str()
              << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  GDALAllRegister();
  CPLPushErrorHandler(CPLQuietErrorHandler);
  if (!CPLGetConfigOption("GDAL_CACHEMAX", nullptr)) CPLSetConfigOption("GDAL_CACHEMAX", "64");
  try {
    return run(parse(std::vector<std::string>(argv + 1, argv + argc)));
  } catch (const dpts::UsageError& e) {
    std::cerr << "dpts-eval: " << e.what() << "\nTry 'dpts-eval --help' for more information.\n";
    return 2;

  } catch (const std::exception& e) {
    std::cerr << "dpts-eval: error: " << e.what() << "\n";
    return 1;
  }
}

// dpts-eval's measure: load and check, then compare surface distances.
#include "api/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/errors.hpp"
#include "core/steiner_graph.hpp"
#include "io/json.hpp"
#include "io/mesh_formats.hpp"
#include "io/sample_points.hpp"
#include "parallel/memory.hpp"

namespace dpts::api {

std::unique_ptr<Evaluation> load(const EvalRequest& request,
                                 const std::function<void(const io::Dem&)>& dem_read) {
  // Each set's pairs live in K x K tables (par::pair_array_bytes, which the geodesics' memory
  // plan counts too): refused where they alone cannot fit (--points before the DEM is read,
  // --sample-points as soon as the file is), not after minutes of work, killed by the kernel
  // or failing as a bare out-of-memory.
  auto check_pairs = [&](const std::string& flag, int points, int sets) {
    const double need = par::pair_array_bytes(points, sets, request.eval.straighten);
    const bool limit = request.max_memory_mb > 0;
    const double have = limit ? static_cast<double>(request.max_memory_mb) * (1 << 20)
                              : static_cast<double>(par::available_memory_bytes());
    if (need <= have) return;
    const std::string n = std::to_string(points);
    throw InputError(flag + ": the " + n + " x " + n + " pairs of " + std::to_string(sets) +
                     (sets == 1 ? " set" : " sets") + " need about " + par::format_bytes(need) +
                     ", more than the " + par::format_bytes(have) + " available" +
                     (limit ? " (--max-memory)" : ""));
  };
  if (request.sample_points.empty()) {
    check_pairs("--points " + std::to_string(request.eval.points), request.eval.points,
                request.eval.sets);
  }
  auto e = std::make_unique<Evaluation>();
  e->dem = io::read_dem(request.dem, io::DemReadOptions{request.t_srs, request.band}, nullptr);
  const io::Dem& dem = e->dem;
  if (dem_read) dem_read(dem);
  // T: the DEM's full-resolution grid TIN, in the output CRS dpts-par uses.
  e->t = dem.grid_mesh();
  const core::TriMesh& t = e->t;
  // T': the mesh.
  io::Mesh ply = io::read_mesh_file(request.mesh);
  io::check_triangles(ply, request.mesh);
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
        throw InputError(request.mesh + ": vertex " + std::to_string(v) + " (" + std::to_string(x) +
                         ", " + std::to_string(y) + ") lies outside " + request.dem +
                         "; is the mesh of another DEM or in another CRS?");
      }
    }
  }
  e->s = core::TriMesh{std::move(ply.xyz), std::move(ply.faces)};
  core::TriMesh& s = e->s;
  // A triangle soup (an STL made PLY) shares no vertex between faces: weld it, so that the
  // Steiner graph sees its shared edges. A face whose corners fall together is refused.
  e->merged = core::weld_identical_vertices(s);
  for (std::size_t f = 0; e->merged > 0 && f < s.faces.size(); ++f) {
    const auto& v = s.faces[f];
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) {
      throw InputError(request.mesh + ": face " + std::to_string(f) +
                       " has two corners at the same position");
    }
  }
  // The sample points given, checked before any heavy work.
  e->options = request.eval;
  if (!request.sample_points.empty()) {
    e->options.sample_xy = io::read_sample_points_file(request.sample_points);
    e->options.sets = static_cast<int>(e->options.sample_xy.size());
    e->options.points = static_cast<int>(e->options.sample_xy[0].size());
    check_pairs(request.sample_points, e->options.points, e->options.sets);
  }

  // Validity of T' over the DEM.
  const std::vector<double> s_xy = core::xy_of(s.xyz);
  e->validity = core::check_mesh(s_xy, s.faces);
  const core::MeshCheck footprint = core::check_mesh(core::xy_of(t.xyz), t.faces);
  e->footprint_area = footprint.area;
  e->footprint_outline = footprint.boundary_length;
  const double tol = dem.to_output ? 0.01 : 1e-6;  // cells; reprojection rounding
  e->over_nodata = core::faces_over_nodata(dem.grid, dem.grid_xy(s_xy), s.faces, tol);

  // Vertical error at every cell centre of T's footprint.
  e->locate_s = std::make_unique<core::PointLocator>(s);
  e->snap = request.snap_m >= 0 ? request.snap_m
                                : (dem.to_output ? 0.5 * dem.frame.metres_per_unit : 0.0);
  double sq = 0;
  for (std::size_t v = 0; v < t.vertex_count(); ++v) {
    const auto hit = e->locate_s->locate(t.xyz[3 * v], t.xyz[3 * v + 1], e->snap);
    if (!hit) {
      ++e->uncovered;
      continue;
    }
    const double dz = hit->point.z - t.xyz[3 * v + 2];
    sq += dz * dz;
    e->vmax = std::max(e->vmax, std::fabs(dz));
    ++e->measured;
  }
  e->rmse = e->measured ? std::sqrt(sq / static_cast<double>(e->measured)) : 0.0;
  // Both meshes' vertices in Z order, now that nothing reports them by number (the faces keep
  // theirs, so the sample points are the same): T comes row by row, a mesh in whatever order
  // its file has, and the geodesics' searches read a face's corners near each other in memory.
  core::order_vertices_spatially(e->t);
  core::order_vertices_spatially(e->s);
  return e;
}

void measure(Evaluation& e, const EvalRequest& request, const core::Progress& progress) {
  par::EvalOptions& eo = e.options;
  eo.snap_m = e.snap;
  // Geodesics in metres, as the heights are: x, y of a CRS in feet (a US State Plane zone)
  // scaled to metres on both meshes and the sample points (in feet, each distance would mix
  // the units: relief flattened 3.28 x, the error understated several times).
  if (const double u = e.dem.metres_per_output_unit; u != 1.0) {
    for (core::TriMesh* m : {&e.t, &e.s}) {
      for (std::size_t v = 0; v < m->vertex_count(); ++v) {
        m->xyz[3 * v] *= u;
        m->xyz[3 * v + 1] *= u;
      }
    }
    for (auto& set : eo.sample_xy) {
      for (auto& p : set) p[0] *= u, p[1] *= u;
    }
  }
  // What the geodesics may use: the limit less what the run holds already, or what is free.
  if (request.max_memory_mb > 0) {
    const std::size_t limit = request.max_memory_mb << 20, held = par::rss_kb() << 10;
    if (limit <= held) {
      throw InputError("--max-memory " + std::to_string(request.max_memory_mb) +
                       ": the run holds " + par::format_bytes(static_cast<double>(held)) +
                       " (DEM and meshes) before its geodesics start");
    }
    eo.memory_budget_bytes = limit - held;
  } else {
    eo.memory_budget_bytes = par::available_memory_bytes();
  }
  try {
    e.result = par::evaluate_distances(e.t, e.s, eo, progress);
  } catch (const std::invalid_argument& err) {  // the mesh's structure (see SteinerGraph)
    throw InputError(request.mesh + ": " + err.what());
  }
}

std::string Evaluation::json(const EvalRequest& request, int threads, double seconds) const {
  const par::EvalResult& r = result;
  const par::EvalOptions& eo = options;
  io::JsonArray sets;
  for (double x : r.set_errors) sets.raw(io::json_number(x));
  // The DEM's warnings of its heights (as on stderr): a batch reads them here.
  io::JsonArray warnings;
  for (const std::string& w : dem.height_warnings) warnings.add(w);
  return io::JsonObject()
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
      .add("sample_points", request.sample_points)
      .add("geodesics", r.exact         ? "exact"
                        : eo.straighten ? "straightened"
                                        : "steiner")
      .add("straightened_paths", r.straightened)
      .add("straighten_failed", r.straighten_failed)
      .add("straighten_passes", r.straighten_passes)
      .add("reroutes", r.reroutes)
      .add("shortened_pairs", r.shortened)
      .add("pairs_measured", r.pairs_measured)
      .add("pairs_unconnected_dem", r.pairs_unconnected)
      .add("pairs_coincident", r.pairs_coincident)
      .add("merged_vertices", merged)
      .add("delta_m", r.delta_m)
      .add("delta_mesh_m", r.delta_mesh_m)
      .add("steiner_nodes_dem", r.original_nodes)
      .add("steiner_nodes_mesh", r.simplified_nodes)
      .add("searched_share_dem", r.original_searched)
      .add("searched_share_mesh", r.simplified_searched)
      .add("one_way_pairs_dem", r.original_one_way)
      .add("one_way_pairs_mesh", r.simplified_one_way)
      .add("snapped_points", r.snapped)
      .add("memory_graphs_bytes", r.graphs_bytes)
      .add("memory_search_bytes", r.search_bytes)
      .add("memory_pairs_bytes", r.pairs_bytes)
      .add("memory_routes_bytes", r.routes_bytes)
      .add("max_searches", r.max_searches)
      .add("faces_not_ccw", validity.clockwise_or_flat)
      .add("bad_edges", validity.bad_edges)
      .add("faces_over_nodata", over_nodata)
      .add("coverage", validity.area / footprint_area)
      .add("boundary_ratio", validity.boundary_length / footprint_outline)
      .add("cells_outside_mesh", uncovered)
      .add("threads", threads)
      .add("dem", request.dem)
      .add("mesh", request.mesh)
      .raw("warnings", warnings.str())
      .add("seconds_geodesics_dem", r.original_s)
      .add("seconds_geodesics_mesh", r.simplified_s)
      .add("seconds", seconds)
      .str();
}

}  // namespace dpts::api

#include "api/simplification.hpp"

#include <stdexcept>
#include <utility>

#include "core/errors.hpp"
#include "core/mesh_check.hpp"
#include "core/qslim.hpp"
#include "core/surface_sampling.hpp"
#include "parallel/memory.hpp"

namespace dpts::api {
namespace {

// "--algo vp", and the default's "--algo qem", as the front end names them.
std::string named(const SimplifyRequest& r) { return r.algo_flag + " " + par::name_of(r.algo); }
std::string default_named(const SimplifyRequest& r) { return r.algo_flag + " qem"; }

std::size_t memory_limit(const SimplifyRequest& r) {
  return r.memory_limit_bytes > 0 ? r.memory_limit_bytes : par::available_memory_bytes();
}

// Reads the DEM whole, refusing first (with the estimate) one whose whole-DEM run would not fit
// in memory.
io::Dem read_whole(io::DemInfo info, const std::string& input, const SimplifyRequest& r,
                   std::size_t bytes_per_cell, const core::Progress& progress) {
  io::check_whole_size(info, named(r) + " (the whole DEM in memory); the default " +
                                 default_named(r) + " reads it in tiles");
  const double need = static_cast<double>(info.cell_count()) * bytes_per_cell;
  const std::size_t limit = memory_limit(r);
  if (need > static_cast<double>(limit)) {
    throw InputError(input + ": " + std::to_string(info.width) + " x " +
                     std::to_string(info.height) + " cells need about " + par::format_bytes(need) +
                     " with " + named(r) + " (the whole DEM in memory), more than the " +
                     par::format_bytes(static_cast<double>(limit)) + " available; the default " +
                     default_named(r) + " (or vp-meta, pld-meta) reads it in tiles");
  }
  return io::read_dem(std::move(info), progress);
}

void input_ready(const SimplifyRequest& r, const io::DemInfo& dem) {
  if (r.on_input) r.on_input(dem);
}

// QSlim (the paper's competitor): Garland-Heckbert edge collapse of the grid TIN, in memory,
// in the frame (core::frame_grid_mesh), its result mapped to the output CRS.
void run_qslim(io::DemInfo info, const std::string& input, const SimplifyRequest& r,
               const core::Progress& progress, Simplification& out) {
  io::Dem dem = read_whole(std::move(info), input, r, core::kQslimBytesPerCell, progress);
  input_ready(r, dem);
  const char* stage = par::name_of(r.algo);
  if (!progress(0.0, stage)) throw Cancelled();
  core::TriMesh grid = core::frame_grid_mesh(dem.grid, dem.frame);
  if (grid.faces.empty()) throw InputError(input + ": " + kNothingToTriangulate);
  if (!progress(0.0, stage)) throw Cancelled();
  out.valid_cells = dem.valid_cells;
  out.input_vertices = grid.vertex_count();
  out.target_vertices = par::target_count(r.keep, out.input_vertices);
  core::QslimStats stats;
  out.mesh = core::qslim(std::move(grid), out.target_vertices, &stats,
                         [&](double f, std::string_view) { return progress(f, stage); });
  if (!progress(1.0, stage)) throw Cancelled();
  out.kept_vertices = stats.kept_vertices;
  out.rejected_folds = stats.rejected_folds;
  dem.frame_mesh_to_output(out.mesh);
  out.height_warnings = dem.height_warnings;
  out.dem = std::move(static_cast<io::DemInfo&>(dem));
}

// vp, pld: the paper's elimination on the whole DEM's Delaunay TIN.
void run_elimination(io::DemInfo info, const std::string& input, const SimplifyRequest& r,
                     const core::Progress& progress, Simplification& out) {
  io::Dem dem = read_whole(std::move(info), input, r, io::DemInfo::kWholeDemBytesPerCell, progress);
  input_ready(r, dem);
  // A reprojected DEM's straight grid outline bends in the output CRS: merged outline edges may
  // stray from it by at most 1 % of a cell, so no face reaches a void cell's centre.
  core::EliminationOptions elimination = r.elimination;
  elimination.importance = par::importance_of(r.algo);
  elimination.outline_chord_ok = dem.outline_chord_test(dem.outline_tolerance_m());
  par::SimplifyStats stats;
  core::Tin tin;
  try {
    tin = par::simplify_dem(dem.grid, dem.frame, elimination, r.keep, progress, &stats);
  } catch (const std::invalid_argument& e) {
    throw InputError(input + ": " + e.what());
  }
  std::vector<double> z(tin.cells.size());
  for (std::size_t i = 0; i < tin.cells.size(); ++i) z[i] = dem.grid.z[tin.cells[i]];
  out.valid_cells = dem.valid_cells;
  out.input_vertices = stats.input_vertices;
  out.target_vertices = stats.target_vertices;
  out.kept_vertices = stats.kept_vertices;
  out.mesh = dem.output_mesh(std::move(tin), z);
  out.height_warnings = dem.height_warnings;
  out.dem = std::move(static_cast<io::DemInfo&>(dem));
}

// The piece engines: qem, vp-meta, pld-meta, out of core.
void run_pieces(const io::DemInfo& dem, const SimplifyRequest& r, const core::Progress& progress,
                Simplification& out) {
  if (par::is_meta(r.algo)) {
    io::check_whole_size(dem, named(r) + " (32-bit cell ids); the default " + default_named(r) +
                                  " reads it in tiles");
  }
  input_ready(r, dem);
  const io::GdalRaster source(dem);
  par::MetaStats& stats = out.pieces;
  if (r.algo == par::Algorithm::qem) {
    par::QemEngineOptions qo;
    qo.keep = r.keep;
    qo.levels = r.levels;
    qo.tile_bytes = r.tile_bytes;
    qo.memory_limit_bytes = memory_limit(r);
    if (r.max_error) qo.max_error = *r.max_error;
    if (r.spill) {
      out.spilled = std::make_shared<io::SpilledMesh>();
      qo.sink = out.spilled.get();
    }
    out.mesh = r.qem_engine ? r.qem_engine(source, qo, progress, stats)
                            : par::simplify_qem(source, qo, progress, &stats);
  } else {
    par::MetaOptions mo;
    mo.elimination = r.elimination;
    mo.elimination.importance = par::importance_of(r.algo);
    mo.keep = r.keep;
    mo.levels = r.levels;
    mo.tile_bytes = r.tile_bytes;
    mo.value_points = r.value_points;
    mo.seed = r.elimination.seed;
    mo.memory_limit_bytes = memory_limit(r);
    par::MetaResult result = par::simplify_meta(source, mo, progress, &stats);
    out.mesh = dem.output_mesh(std::move(result.tin), result.z);
  }
  out.piece_engine = true;
  out.valid_cells = stats.valid_cells;
  out.input_vertices = stats.input_vertices;
  out.target_vertices = stats.target_vertices;
  out.kept_vertices = stats.kept_vertices;
  out.height_warnings = io::height_warnings(dem, stats.absurd_cells, stats.usual_nodata_cells);
}

}  // namespace

Simplification simplify(io::DemInfo dem, const std::string& input, const SimplifyRequest& request,
                        const core::Progress& progress) {
  Simplification out;
  switch (request.algo) {
    case par::Algorithm::qslim:
      run_qslim(std::move(dem), input, request, progress, out);
      break;
    case par::Algorithm::vp:
    case par::Algorithm::pld:
      run_elimination(std::move(dem), input, request, progress, out);
      break;
    case par::Algorithm::vp_meta:
    case par::Algorithm::pld_meta:
    case par::Algorithm::qem:
      run_pieces(dem, request, progress, out);
      out.dem = std::move(dem);
      // note: the count pass finds them (a whole-DEM read notes them itself): in the report
      // too, where a batch's user reads them.
      out.dem.notes.insert(out.dem.notes.end(), out.height_warnings.begin(),
                           out.height_warnings.end());
      break;
  }
  // note: the TIN is built in a local affine frame; a projection far from affine could fold a
  // sliver in the output CRS. Refuse such a mesh rather than hide it. (qem's merge counts them
  // as it writes its faces, the same test.)
  const std::size_t folded =
      request.algo == par::Algorithm::qem
          ? out.pieces.folded_faces
          : core::check_mesh(core::xy_of(out.mesh.xyz), out.mesh.faces).clockwise_or_flat;
  if (folded != 0) {
    throw InputError(input + ": " + std::to_string(folded) + " faces would fold over in " +
                     out.dem.output_crs_name);
  }
  return out;
}

}  // namespace dpts::api

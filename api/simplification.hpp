// Simplification of an opened DEM by any of the methods, into a mesh in the output CRS: what
// dpts-par, dpts-mpi and the library's dpts::simplify all run. The front ends parse their
// options, name the output and write it; this runs the method.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "core/elimination.hpp"
#include "core/mesh.hpp"
#include "core/progress.hpp"
#include "core/raster_source.hpp"
#include "io/dem_reader.hpp"
#include "io/spilled_mesh.hpp"
#include "parallel/meta.hpp"
#include "parallel/qem_engine.hpp"
#include "parallel/simplify.hpp"

namespace dpts::api {

// The qem piece engine: par::simplify_qem, or dpts-mpi's, which spreads the pieces over ranks.
using QemEngine =
    std::function<core::TriMesh(const core::RasterSource&, const par::QemEngineOptions&,
                                const core::Progress&, par::MetaStats&)>;

struct SimplifyRequest {
  par::Algorithm algo = par::Algorithm::qem;
  // How messages name the front end's option for the method: "--algo" in dpts-par, "algo" in
  // the library ("--algo vp (the whole DEM in memory)...").
  std::string algo_flag = "--algo";
  par::KeepTarget keep;
  int levels = 4;                        // k-d levels of the piece engines
  std::size_t tile_bytes = 256u << 20;   // a piece's raster window, at most
  std::optional<double> max_error;       // qem: vertical error bound (output CRS units)
  int value_points = 20;                 // vp-meta, pld-meta: points per piece value
  core::EliminationOptions elimination;  // vp, pld and the meta methods (importance from algo)
  std::size_t memory_limit_bytes = 0;    // what the run may use; 0: what is available now
  QemEngine qem_engine;                  // empty: par::simplify_qem
  // qem: the merge writes the mesh to temporary files as it becomes final
  // (Simplification::spilled) instead of holding it whole; the other methods ignore it.
  bool spill = false;
  // Called once the input is known to be valid (read whole for vp, pld and qslim), before the
  // work: where a front end claims its output and prints the DEM's notes.
  std::function<void(const io::DemInfo&)> on_input;
};

struct Simplification {
  io::DemInfo dem;     // the input's description, given back
  core::TriMesh mesh;  // x, y in the output CRS, heights in metres
  // With SimplifyRequest::spill and qem: the mesh, on disk (`mesh` is then empty).
  std::shared_ptr<io::SpilledMesh> spilled;
  std::size_t face_count() const { return spilled ? spilled->face_count() : mesh.faces.size(); }
  std::size_t valid_cells = 0, input_vertices = 0, target_vertices = 0, kept_vertices = 0;
  // The piece engines' (qem, vp-meta, pld-meta) stages and pieces; pieces empty otherwise.
  par::MetaStats pieces;
  bool piece_engine = false;
  std::size_t rejected_folds = 0;  // qslim: collapses refused (fold or link condition)
  // The warnings of the heights read (io::height_warnings), by any method: a whole-DEM read's,
  // or the piece engines' count pass's.
  std::vector<std::string> height_warnings;
};

// Runs request.algo on the DEM (`input`: its name in messages). Whole-DEM methods (vp, pld,
// qslim) read it whole, refused first (InputError, with the estimate) when that would not fit in
// memory_limit_bytes. A mesh that would fold over in the output CRS is refused (InputError).
Simplification simplify(io::DemInfo dem, const std::string& input, const SimplifyRequest& request,
                        const core::Progress& progress);

}  // namespace dpts::api

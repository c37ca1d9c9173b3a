// The measure dpts-eval prints and the library's dpts::evaluate returns: a DEM and a mesh read
// and checked (load), then their surface distances compared (measure).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "core/mesh_check.hpp"
#include "core/steiner_graph.hpp"
#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"
#include "parallel/evaluate.hpp"

namespace dpts::api {

struct EvalRequest {
  std::string dem, mesh, t_srs;
  int band = 1;               // the DEM's band holding the heights (1-based)
  std::string sample_points;  // a --sample-points file, or empty
  par::EvalOptions eval;
  double snap_m = -1;             // < 0: 0, or half a cell where the DEM is reprojected
  std::size_t max_memory_mb = 0;  // 0: what is available when the geodesics start
};

// A DEM and a mesh on it, with everything dpts-eval reports.
struct Evaluation {
  io::Dem dem;
  core::TriMesh t, s;        // the DEM's grid TIN; the mesh (welded): x, y in the output
                             // CRS's unit, in metres once measure() ran (a CRS in feet)
  std::size_t merged = 0;    // mesh vertices welded into an earlier one
  core::MeshCheck validity;  // of the mesh
  double footprint_area = 0;
  double footprint_outline = 0;  // the length of T's boundary (MeshCheck::boundary_length)
  std::size_t over_nodata = 0;  // mesh faces over no-data cells
  double snap = 0;              // metres
  double rmse = 0, vmax = 0;    // vertical error at T's vertices inside the mesh
  std::size_t measured = 0, uncovered = 0;
  par::EvalOptions options;                      // the request's, with its sample points read
  par::EvalResult result;                        // set by measure()
  std::unique_ptr<core::PointLocator> locate_s;  // the mesh's faces by position (before measure)

  // dpts-eval --json's object.
  std::string json(const EvalRequest& request, int threads, double seconds) const;
};

// Reads the DEM (T: its grid TIN) and the mesh, and checks them: pair tables that cannot fit,
// a mesh far outside the DEM (another DEM's, or another CRS), a triangle soup (welded; faces
// whose corners fall together refused), the sample points; then the mesh's validity over the
// DEM and its vertical error. Throws InputError / IoError naming the file. `dem_read`, if
// given, is called once the DEM is read, before the mesh is (to check outputs against it).
std::unique_ptr<Evaluation> load(const EvalRequest& request,
                                 const std::function<void(const io::Dem&)>& dem_read = {});

// The surface distances compared (par::evaluate_distances), in the calling arena, in metres
// (x, y of both meshes scaled first where the output CRS is in feet).
void measure(Evaluation& e, const EvalRequest& request, const core::Progress& progress);

}  // namespace dpts::api

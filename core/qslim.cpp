// QSlim baseline: Garland-Heckbert edge collapse with a locked outline and no folds, on dpts's
// own collapse kernel (core/qem.cpp) with CGAL's GarlandHeckbert_plane_policies' quadrics.
#include "core/qslim.hpp"

#include <utility>

#include "core/qem.hpp"

namespace dpts::core {

TriMesh qslim(TriMesh in, std::size_t keep, QslimStats* stats, const Progress& progress) {
  // note: the rules of the CGAL Surface_mesh_simplification version this replaced (which
  // took 5.6-6.6 x its CPU on San Gabriel, issue 20): unit-normal plane quadrics, outline
  // edges' quadrics at CGAL's discontinuity multiplier (100), the quadric's cost alone, its
  // optimum (else the best point of the edge), border edges constrained and a collapse next
  // to the border onto the border vertex (Constrained_placement), no fold seen from above.
  // Ties and rounding differ, so the meshes do too (README, "QSlim").
  QemOptions options;
  options.area_weight = 0;
  options.plane_quadrics = true;
  options.outline_weight = 100;
  options.lock_outline = true;
  QemResult r = qem_simplify(std::move(in), keep, std::move(options), progress);
  QslimStats local;
  QslimStats& st = stats ? *stats : local;
  st.input_vertices = r.input_vertices;
  st.kept_vertices = r.mesh.vertex_count();
  st.rejected_folds = r.refused;
  return std::move(r.mesh);
}

}  // namespace dpts::core

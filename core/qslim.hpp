// The paper's reference competitor, QSlim (Garland and Heckbert's quadric edge collapse, plane
// quadrics), on dpts's collapse kernel (core/qem.hpp; until issue 20 through CGAL's
// Surface_mesh_simplification with the Garland-Heckbert plane policies, whose rules it keeps),
// adapted so that it can be compared with the elimination methods on a DEM:
//   - the outline of the valid footprint (the mesh border, voids included) is locked: border
//     edges are never collapsed and a collapse never moves a border vertex, so the footprint
//     does not shrink;
//   - a collapse that would fold a triangle over (or flatten it) seen from above is rejected,
//     so the result stays a height field;
//   - it stops at an exact vertex count.
// Unlike elimination, QSlim places each merged vertex at its quadric's optimum: the output
// vertices are not a subset of the DEM's cells.
#pragma once

#include <cstddef>

#include "core/elimination.hpp"
#include "core/steiner_graph.hpp"

namespace dpts::core {

// Bytes a QSlim run holds per raster cell (grid, surface mesh with quadrics and the collapse
// queue), measured with some margin: 434 on San Gabriel, 370 on pyrenees_srtm3 (505 through
// CGAL's kernel, before issue 20).
inline constexpr std::size_t kQslimBytesPerCell = 480;

struct QslimStats {
  std::size_t input_vertices = 0, kept_vertices = 0;
  // collapses refused at the top of the queue: a triangle would fold, or the topology
  std::size_t rejected_folds = 0;
};

// Simplifies a triangle mesh (counter-clockwise faces seen from above, in metres) to `keep`
// vertices, or as few as the locked border and the fold rule allow. Returns the new mesh.
// progress (stage "simplify") is asked every few thousand cost computations and collapses,
// from the first (the queue's costs take seconds on large meshes); false stops it with
// Cancelled.
// The mesh is taken by value: move it in to save its memory while it runs.
TriMesh qslim(TriMesh mesh, std::size_t keep, QslimStats* stats = nullptr,
              const Progress& progress = nullptr);

}  // namespace dpts::core

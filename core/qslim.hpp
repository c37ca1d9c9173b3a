// The paper's reference competitor, QSlim (Garland and Heckbert's quadric edge collapse), via
// CGAL's Surface_mesh_simplification with the Garland-Heckbert plane policies, adapted so that
// it can be compared with the elimination methods on a DEM:
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
#include <cstdint>
#include <functional>

#include "core/steiner_graph.hpp"

namespace dpts::core {

// Bytes a QSlim run holds per raster cell (grid, surface mesh with quadrics and the collapse
// queue), measured on real DEMs with some margin (README, memory).
inline constexpr std::size_t kQslimBytesPerCell = 560;

struct QslimStats {
  std::size_t input_vertices = 0, kept_vertices = 0;
  std::size_t rejected_folds = 0;  // collapses refused because a triangle would fold
};

// What a collapse may do to the outline of the footprint.
enum class Outline {
  kLocked,  // no vertex of it moves or goes (the paper's comparison)
  // A vertex where the outline runs straight on (collinear seen from above with its two
  // outline neighbours, exactly) may go, collapsed onto one of those neighbours: the footprint
  // stays exactly the same, and the vertices a rectangle's sides held go to the interior.
  kStraightRunsFree,
};

struct QslimOptions {
  Outline outline = Outline::kLocked;
  // With kStraightRunsFree: whether the outline may run straight from vertex a to vertex b
  // (mesh vertex ids), for a mesh whose coordinates are a linear stand-in for the output CRS
  // (a reprojected DEM's frame); null: always.
  std::function<bool(std::uint32_t a, std::uint32_t b)> outline_chord_ok;
  // Whether a triangle (corners a, b, c, counter-clockwise seen from above) may be made: a
  // collapse after which any triangle of its star fails is refused (a bound on the vertical
  // error, --max-error). Null: always.
  std::function<bool(const double* a, const double* b, const double* c)> triangle_ok;
};

// Simplifies a triangle mesh (counter-clockwise faces seen from above, in metres) to `keep`
// vertices, or as few as the outline rule and the fold rule allow. Returns the new mesh.
TriMesh qslim(const TriMesh& mesh, std::size_t keep, QslimStats* stats = nullptr,
              const QslimOptions& options = {});

}  // namespace dpts::core

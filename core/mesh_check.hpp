// Structural checks of a triangle mesh seen from above: orientation, edge use and area.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/grid.hpp"
#include "core/steiner_graph.hpp"

namespace dpts::core {

struct MeshCheck {
  std::size_t faces = 0;
  std::size_t clockwise_or_flat = 0;  // faces not strictly counter-clockwise in x, y
  std::size_t bad_edges = 0;          // edges used twice in one direction or by > 2 faces
  std::size_t boundary_edges = 0;     // edges used by exactly one face
  // Their summed lengths in x, y: the outline's, where the faces cover a footprint without
  // a crack (a T-junction, or a seam whose two sides were not joined, adds its length twice).
  double boundary_length = 0.0;
  double area = 0.0;                  // sum of signed face areas in x, y
};

// Counter-clockwise faces whose interior edges are each shared by exactly two faces in
// opposite directions form a proper planar subdivision of their union; with area equal to
// the footprint's, they cover it exactly once.
MeshCheck check_mesh(const std::vector<double>& xy,  // x0, y0, x1, y1, ...
                     const std::vector<std::array<std::uint32_t, 3>>& faces);

// Twice the signed area in x, y of the triangle a, b, c (x, y, z triples): > 0 when
// counter-clockwise. check_mesh's test of a face.
inline double twice_area_xy(const double* a, const double* b, const double* c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Sum of signed face areas in x, y (positive for counter-clockwise faces).
double mesh_area(const std::vector<double>& xy,
                 const std::vector<std::array<std::uint32_t, 3>>& faces);

// x, y of each vertex (x0, y0, x1, y1, ...) from x, y, z triples.
std::vector<double> xy_of(const std::vector<double>& xyz);

// Number of faces that contain (closed, in grid space) the centre of a no-data cell or reach
// outside the grid. grid_xy holds each vertex's grid position (col, row) as doubles;
// `tolerance` (in cells) absorbs rounding from coordinate transformations.
std::size_t faces_over_nodata(const HeightGrid& grid, const std::vector<double>& grid_xy,
                              const std::vector<std::array<std::uint32_t, 3>>& faces,
                              double tolerance = 1e-6);

// Welds a triangle soup (each face with its own corners, as an STL converted to PLY): vertices
// with identical x, y and z become one, the first of them in index order, and faces index it;
// the vertices kept stay in their order. Returns the number of vertices merged away (0 when
// none share a position). A face whose corners fall together becomes one that repeats a
// vertex: the caller checks. Deterministic; O(n log n).
std::size_t weld_identical_vertices(TriMesh& mesh);

}  // namespace dpts::core

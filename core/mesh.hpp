// The two forms of a triangle mesh in dpts: by coordinates (TriMesh: what is measured, written
// and read) and by raster cells (Tin: what is simplified, its vertices cells of one DEM).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dpts::core {

// A triangle mesh: x, y in a metric CRS (or a grid frame), z height. Faces index the vertices,
// counter-clockwise seen from above unless said otherwise.
struct TriMesh {
  std::vector<double> xyz;  // x0, y0, z0, x1, ...
  std::vector<std::array<std::uint32_t, 3>> faces;
  std::size_t vertex_count() const { return xyz.size() / 3; }
};

// Where an engine hands a mesh over as its parts become final, instead of holding it whole
// (the qem engine's merge): each call's vertices (x, y, z) follow those of earlier calls, and
// its faces index all vertices handed over so far, its own included.
class MeshSink {
 public:
  virtual ~MeshSink() = default;
  virtual void add(const std::vector<double>& xyz,
                   const std::vector<std::array<std::uint32_t, 3>>& faces) = 0;
};

// A TIN over a DEM: vertices are cells (row-major indices, ascending), faces index into
// `cells`. Who makes one says more: the elimination's (elimination.hpp) are counter-clockwise,
// rotated to their smallest index and sorted, and cover the valid footprint exactly once;
// grid_tin's (surface_sampling.hpp) are the full-resolution grid TIN in the grid's orientation.
struct Tin {
  std::vector<std::uint32_t> cells;
  std::vector<std::array<std::uint32_t, 3>> faces;
};

}  // namespace dpts::core

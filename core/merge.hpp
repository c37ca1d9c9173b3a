// The last stage of the meta method PLD'/VP' (the DPTS paper, section 3.2): the Delaunay
// triangulation of the vertices every piece kept, with the footprint labelled from the pieces'
// outline edges, so that no whole-DEM state but the kept vertices is needed.
#pragma once

#include <cstdint>
#include <vector>

#include "core/elimination.hpp"
#include "core/grid.hpp"

namespace dpts::core {

// cells: the kept cells (row-major indices of a raster `width` columns wide), ascending.
// outline: every outline edge of the footprint between kept cells, directed with the footprint
// on its left (duplicates allowed). Triangulates the cells in the frame and keeps the faces
// reached from the left of an outline edge without crossing one. Throws std::logic_error if an
// outline edge is not an edge of the triangulation (the pieces' chord rule prevents that).
Tin merge_kept(int width, const GridFrame& frame, const std::vector<std::uint32_t>& cells,
               const std::vector<OutlineEdge>& outline);

}  // namespace dpts::core

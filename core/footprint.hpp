// The valid footprint F of a DEM: the part of the plane a TIN of it may cover.
//
// F is the union, over all grid squares (4 neighbouring cell centres), of the whole square
// when its 4 corners are valid, or of the triangle of its 3 valid corners when exactly one
// is no-data. Triangles never touch a no-data cell, so voids and concave outlines stay
// open. A cell is a *surface vertex* when it is a corner of some part of F; isolated valid
// cells and one-cell-wide strands carry no surface and are dropped.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/grid.hpp"

namespace dpts::core {

// Indices (row-major, ascending) of the cells that are corners of F.
std::vector<std::uint32_t> surface_cells(const HeightGrid& grid);

// Whether the point (sum_col / 3, sum_row / 3) of grid space, pushed by an infinitesimal
// (+eps, +eps^2), lies inside F. With sums of the three corners of a triangle this is the
// triangle's centroid: the push makes the answer exact and unambiguous on grid lines, so a
// triangle that does not cross the outline of F is classified without rounding.
bool footprint_contains_third(const HeightGrid& grid, std::int64_t sum_col, std::int64_t sum_row);

// Precomputed valid-corner masks of all grid squares, for fast repeated
// footprint_contains_third() tests (one byte per cell).
class FootprintIndex {
 public:
  explicit FootprintIndex(const HeightGrid& grid);
  bool contains_third(std::int64_t sum_col, std::int64_t sum_row) const;

 private:
  std::int64_t width_ = 0, height_ = 0;
  bool full_ = false;               // every square whole: mask_ is empty
  std::vector<std::uint8_t> mask_;  // square (c, r) at r * width + c
};

// Area of F in cell units (a full square counts 1, a three-corner triangle 1/2).
double footprint_area_cells(const HeightGrid& grid);

}  // namespace dpts::core

// The division stage of the meta method PLD'/VP' (the DPTS paper, section 4.3): a k-d split
// of the DEM into rectangular pieces with about equal numbers of surface vertices.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace dpts::core {

// Surface-vertex counts of a raster per square block of `block` x `block` cells (the last
// row and column of blocks may be partial), gathered in one streaming pass. Split lines fall
// on block lines, so a piece's count is an exact sum of block counts.
struct BlockCounts {
  int width = 0, height = 0;  // raster size in cells
  int block = 16;
  int blocks_x = 0, blocks_y = 0;
  std::vector<std::uint32_t> counts;  // blocks_y rows of blocks_x
  // Of them, those beside a no-data cell (one of their four neighbours): where the outline of
  // the valid data bends round voids. Empty where not counted.
  std::vector<std::uint32_t> outline;
  std::uint32_t at(int bx, int by) const {
    return counts[static_cast<std::size_t>(by) * blocks_x + bx];
  }
};

// A piece: cells [col0, col0 + width) x [row0, row0 + height), its surface vertices and, of
// them, those beside a no-data cell (BlockCounts::outline; 0 where not counted).
struct Piece {
  int col0 = 0, row0 = 0, width = 0, height = 0;
  std::size_t vertices = 0;
  std::size_t outline = 0;
};

struct DivisionOptions {
  int levels = 4;                         // at least 2^levels pieces where the blocks allow
  std::size_t budget_bytes = 256 << 20;   // a piece's estimated working set must fit
  int halo = 8;                           // context cells round a piece (counted in its memory)
  std::size_t max_vertices = 0;           // a piece with more surface vertices splits (0: any)
  double col_metres = 1, row_metres = 1;  // cell size, to split across the longer side
};

// Estimated working set of a piece: its window's heights and footprint masks, and the
// Delaunay TIN and elimination state of its surface vertices (measured; see README).
inline constexpr std::size_t kBytesPerWindowCell = 10;
inline constexpr std::size_t kBytesPerVertex = 320;
std::size_t piece_bytes(const Piece& piece, int halo);

// Splits the raster recursively, across its longer side in metres, at the block line that
// best halves the surface vertices, until every piece is `levels` deep, fits the budget and
// has a window (with its halo) of fewer than 2^32 cells (or is a single block). Pieces with no
// surface vertex are dropped. Deterministic; pieces come in k-d order.
std::vector<Piece> kd_divide(const BlockCounts& counts, const DivisionOptions& options);

}  // namespace dpts::core

// The piece engine for qem (dpts's quadric edge collapse, core/qem.hpp): out of core and
// concurrent, as the meta engine, but with one global collapse order at the end.
//
//  1. One streaming pass counts surface vertices per block; a k-d division cuts the raster
//     into pieces that fit the tile budget (as for vp-meta).
//  2. oneTBB tasks read each piece's window (its cells and one more column and row, so that
//     every grid square belongs to exactly one piece) through their own GDAL handles, build
//     its grid TIN and collapse it with the seam vertices (those other windows share) locked,
//     down to `slack` x its share of the target. The window is then freed: what a piece
//     hands on is its kept vertices, their accumulated quadrics and its faces.
//  3. The merge stitches the pieces at their seam vertices (identical cells), sums those
//     vertices' quadrics (so every vertex's quadric is what one whole-DEM run would have
//     given), unlocks the seams and goes on collapsing to the target: the seams vanish, and
//     the last collapses follow one global cost order, not per-piece budgets.
// With a vertical bound (--max-error) every new triangle is tested against the valid cell
// centres it covers: in a piece from its window, in the merge from the DEM read again block
// by block through a cache of at most one tile.
// Pieces are simplified independently and merged in k-d order, so the output does not depend
// on the number of threads.
#pragma once

#include <cstddef>

#include "core/elimination.hpp"
#include "core/raster_source.hpp"
#include "core/steiner_graph.hpp"
#include "parallel/meta.hpp"
#include "parallel/simplify.hpp"

namespace dpts::par {

struct QemEngineOptions {
  KeepTarget keep;
  int levels = 4;                                   // at least 2^levels pieces
  std::size_t tile_bytes = std::size_t{256} << 20;  // one piece's working set must fit
  // Each piece keeps slack x its share of the target (plus its seams) for the merge, which
  // then chooses among them in one order: more is closer to one whole-DEM run, and costs
  // memory and serial time in the merge.
  double slack = 1.3;
  // The vertical error at every valid cell centre stays <= max_error metres (0: no bound);
  // the count may then stay above the target.
  double max_error = 0;
  // Refuse (InputError, with the estimate) a run estimated to need more memory; 0: no check.
  std::size_t memory_limit_bytes = 0;
};

// Bytes the qem engine holds per kept vertex in the merge (the pieces' outputs and the merged
// mesh being collapsed), measured with some margin.
inline constexpr std::size_t kQemBytesPerKeptVertex = 700;

// Runs the engine on band 1. The mesh is in the output CRS (heights in metres), faces
// counter-clockwise. stats gets the counts, the pieces (value 0) and
// the stage times. Progress stages "count", "simplify", "merge"; false stops with Cancelled.
core::TriMesh simplify_qem(const core::RasterSource& dem, const QemEngineOptions& options,
                           const core::Progress& progress, MetaStats* stats = nullptr);

}  // namespace dpts::par

// The piece engine for qem (dpts's quadric edge collapse, core/qem.hpp): out of core and
// concurrent, as the meta engine, but with one global collapse order at the end.
//
//  1. One streaming pass counts surface vertices per block; a k-d division cuts the raster
//     into pieces that fit the tile budget (as for vp-meta).
//     Then the pilot: a spread of the pieces (every 32nd in k-d order, at least 8) collapsed
//     down to a quarter of their shares of the target, each collapse's cost noted, gives the
//     cost bound at which they would keep, together, `slack` x their shares. Where a copy of
//     a pilot piece's collapse (taken at twice its share) made no collapse over the bound, it
//     goes on from there to the piece's output, the same as step 2 would make.
//  2. oneTBB tasks read each piece's window (its cells and one more column and row, so that
//     every grid square belongs to exactly one piece) through their own GDAL handles, build
//     its grid TIN and collapse it with the seam vertices (those other windows share) locked,
//     while a collapse costs at most the pilot's bound (between a quarter and 8 x its share
//     of the target): a rough piece keeps more than a flat one, as one collapse of the whole
//     DEM would. (Without a bound, near 100 %, or with --max-error: down to `slack` x its
//     share.) The window is then freed: what a piece hands on is its kept vertices, their
//     accumulated quadrics and its faces.
//  3. The merge stitches the pieces at their seam vertices (identical cells), sums those
//     vertices' quadrics (so every vertex's quadric is what one whole-DEM run would have
//     given), unlocks the seams and goes on collapsing to the target: the seams vanish, and
//     the last collapses follow one cost order, not per-piece budgets. When one group holds
//     all the pieces, runs of 4 consecutive pieces first take the merge's cheapest collapses
//     concurrently, each run stitched at its own seams, below a cost bound the merge passes
//     anyway (the pre-merge, qem_engine.cpp): the serial merge is left the rest.
// The merge takes the pieces in groups (consecutive in k-d order) whose kept vertices fit the
// tile budget (planned at `slack` x their shares: a group of rough pieces holds more): a DEM
// whose kept vertices all fit is one group, merged as above. Otherwise
// steps 2 and 3 run a group at a time, each group's merge beside the next group's pieces (so
// that only the last group's merge is serial), and the memory the merge holds no longer grows
// with the DEM (the output mesh going to options.sink): each group's pieces are simplified,
// stitched to what is still open of the groups before, and collapsed with it down to the target's
// share of the pieces merged so far (the last group: the target), the vertices a later piece's
// window shares locked. Then every vertex more than a few edges from those is final: it is written
// to the output with the faces whose corners are all final, and leaves the merge. The band left
// open lets the next group simplify the seam between them with the vertices around it; across
// groups the target is shared by what the pieces kept (the later ones' estimated from their
// vertices beside voids and the rest, at rates fitted over the pilot's pieces, which with
// several groups include the pieces most beside voids), the vertices no collapse removes (the
// outlines round voids, estimated too) set apart first; within one it follows the cost order. With a vertical bound
// (--max-error) every new triangle is tested against the valid cell centres it covers: in a piece
// from its window, in the merge from the DEM read again block by block through a cache of at most
// one tile. Pieces are simplified independently and merged in k-d order, so the output does not
// depend on the number of threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/elimination.hpp"
#include "core/qem.hpp"
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
  // The merge's budget for one group's kept vertices (bytes, at kQemBytesPerKeptVertex);
  // 0: tile_bytes.
  std::size_t merge_bytes = 0;
  // Where the merge writes the mesh as its parts become final (in the output CRS); the engine
  // then returns an empty mesh. Null: the engine returns the mesh.
  core::MeshSink* sink = nullptr;
  // The pre-merge (qem_engine.cpp) runs when one group holds all the pieces and they hand on
  // at least this many vertices. note: a smaller merge takes milliseconds; there the pre-merge
  // would change the mesh (its frozen seams are a larger part of each run: 16 cases of 4 DEMs
  // of 128 x 128 at 10 to 70 %, distance error -2.0 to +2.5 %, vertical RMSE up to +1 %) for
  // no time worth having.
  std::size_t premerge_vertices = std::size_t{1} << 16;
  // Refuse (InputError, with the estimate) a run estimated to need more memory; 0: no check.
  std::size_t memory_limit_bytes = 0;
};

// Bytes the qem engine holds per kept vertex in the merge (the pieces' outputs and the merged
// mesh being collapsed), measured with some margin.
inline constexpr std::size_t kQemBytesPerKeptVertex = 700;
// Bytes a piece's output holds per kept vertex until its group's merge (San Gabriel to 10 %:
// 131), with some margin: the next group's outputs are held beside a group's merge.
inline constexpr std::size_t kQemBytesPerPieceVertex = 160;
// Bytes of the output mesh per vertex (its coordinates and about two faces).
inline constexpr std::size_t kQemBytesPerOutputVertex = 64;

// The merge's groups of pieces (qem_engine.hpp's note): group g is pieces [starts[g],
// starts[g + 1]); the last entry is pieces.size(). fraction: the target over the surface
// vertices. Depends on the pieces and options alone (not on the threads).
std::vector<std::size_t> qem_groups(const std::vector<core::Piece>& pieces, double fraction,
                                    const QemEngineOptions& options);

// What a piece hands to the merge: its simplified mesh (frame units), and per vertex its
// quadric, its raster cell (where it started), whether it lies on a seam (shared with another
// piece's window), and its x, y on the grid (reprojected DEMs only).
struct QemPieceMesh {
  core::TriMesh mesh;
  std::vector<core::Quadric> quadrics;
  std::vector<std::uint64_t> cell;
  std::vector<char> seam;
  std::vector<double> plane_xy;
  std::size_t bytes() const {
    return (mesh.xyz.capacity() + plane_xy.capacity()) * sizeof(double) +
           mesh.faces.capacity() * sizeof(mesh.faces[0]) +
           quadrics.capacity() * sizeof(core::Quadric) + cell.capacity() * sizeof(std::uint64_t) +
           seam.capacity();
  }
};

// Runs the engine on band 1. The mesh is in the output CRS (heights in metres), faces
// counter-clockwise; with options.sink it goes there, and the mesh returned is empty. stats gets
// the counts, the pieces (value 0) and the stage times. Progress stages "count", "pilot",
// "simplify", "merge"; false stops with Cancelled.
core::TriMesh simplify_qem(const core::RasterSource& dem, const QemEngineOptions& options,
                           const core::Progress& progress, MetaStats* stats = nullptr);

// The engine in its three stages, for running the pieces elsewhere (dpts-mpi): every process
// plans the same pieces, each simplifies its share, and one merges them all; the mesh is the
// same bytes as simplify_qem's, which is these three in one process.
// 1. The streaming count, the division, the memory check and the pilot (every process runs
// it, to the same bound): the pieces, in k-d order; st gets the counts, the pilot's bound and
// a report per piece. With outputs (sized to the pieces), the pilot's pieces it took to their
// end are there, their reports marked by_pilot (stage 2 passes them); else stage 2 simplifies
// them again.
std::vector<core::Piece> plan_qem(const core::RasterSource& dem, const QemEngineOptions& options,
                                  const core::Progress& progress, MetaStats& st,
                                  std::vector<QemPieceMesh>* outputs = nullptr);
// 2. Pieces `which` (indices into pieces) simplified concurrently into outputs[i] (outputs
// sized to the pieces), their reports into st.pieces[i], but for those by_pilot. Progress
// stage "simplify".
void simplify_qem_pieces(const core::RasterSource& dem, const QemEngineOptions& options,
                         const std::vector<core::Piece>& pieces,
                         const std::vector<std::size_t>& which, MetaStats& st,
                         std::vector<QemPieceMesh>& outputs, const core::Progress& progress);
// 3. All pieces' outputs (emptied) stitched at the seams and collapsed on to the target, a
// group at a time as simplify_qem does: the mesh in the output CRS. Progress stage "merge".
core::TriMesh merge_qem(const core::RasterSource& dem, const QemEngineOptions& options,
                        const std::vector<core::Piece>& pieces, std::vector<QemPieceMesh>& outputs,
                        MetaStats& st, const core::Progress& progress);

// A piece's output and report as bytes for another process of the same build, and back;
// from_bytes throws std::runtime_error on bytes that are not one.
std::string to_bytes(const QemPieceMesh& mesh, const PieceReport& report);
void from_bytes(const std::string& bytes, QemPieceMesh& mesh, PieceReport& report);

}  // namespace dpts::par

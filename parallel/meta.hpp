// The meta method PLD'/VP' (the DPTS paper, sections 3.2 and 4.3) as a parallel, out-of-core
// engine: a streaming count pass, a k-d division into pieces, piece values and P2L budgets,
// oneTBB tasks that read (from one core::RasterSource) and simplify pieces concurrently,
// and one Delaunay merge of the kept vertices. Only the kept vertices (and a small count grid)
// are held for the whole DEM; everything else lives as long as one piece.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/elimination.hpp"
#include "core/kd_division.hpp"
#include "core/raster_source.hpp"
#include "parallel/simplify.hpp"

namespace dpts::par {

struct MetaOptions {
  core::EliminationOptions elimination;  // importance and VP settings for every piece
  KeepTarget keep;
  int levels = 4;                                   // at least 2^levels pieces
  std::size_t tile_bytes = std::size_t{256} << 20;  // one piece's working set must fit
  int halo = 8;                                     // context cells round each piece
  int value_points = 20;                            // l: random points per piece value
  int value_cells = 4096;  // piece values on a grid of at most this many cells
  std::uint64_t seed = 1;
  // Refuse (InputError, with the estimate) a run estimated to need more memory; 0: no check.
  std::size_t memory_limit_bytes = 0;
};

// Bytes the meta engine holds per kept vertex (its cell, height, outline and tail records and
// the final triangulation), measured on real DEMs with some margin (README, memory).
inline constexpr std::size_t kMetaBytesPerKeptVertex = 300;

// The meta engine's memory estimate: kept vertices plus the pieces in flight (pieces_bytes).
std::size_t meta_memory_estimate(std::size_t kept_vertices, std::size_t pieces_bytes);

struct PieceReport {
  core::Piece piece;
  double value = 0;        // mean ED/GD of the piece's random point pairs
  std::size_t budget = 0;  // vertices the piece should keep
  std::size_t kept = 0;    // vertices it kept (more than budget when its outline needs them)
  double read_s = 0, simplify_s = 0;  // this piece's own times (simplify: triangulate to end)
  bool by_pilot = false;  // qem: its output made by the pilot (plan_qem), not simplified again
};

struct MetaStats {
  std::size_t input_vertices = 0, target_vertices = 0, kept_vertices = 0;
  std::size_t valid_cells = 0;
  std::size_t absurd_cells = 0;  // implausible heights read as no-data (RasterSource::Implausible)
  // Cells holding a usual no-data value other than the band's (RasterSource::Implausible).
  core::UsualNoDataCounts usual_nodata_cells{};
  int block = 0;
  std::vector<PieceReport> pieces;
  // Wall time per stage.
  double count_s = 0, values_s = 0, simplify_s = 0, merge_s = 0;
  // qem: the merge's concurrent pre-merge (part of merge_s) and the collapses it made.
  double premerge_s = 0;
  std::size_t premerge_collapses = 0;
  // qem: the groups its merge took the pieces in (one when their kept vertices fit a tile).
  std::size_t merge_groups = 0;
  // qem: its pilot (qem_engine.hpp): the pieces it simplified, its time, the cost bound it
  // found for the pieces' collapses (-1: none; the pieces keep their shares by size) and
  // the vertices a piece keeps at that bound (fitted over the pilot's pieces).
  std::size_t pilot_pieces = 0;
  std::size_t pilot_finished = 0;  // of them, those it took on to their outputs (by_pilot)
  double pilot_s = 0;
  double piece_cost_bound = -1;
  double merge_cost_cap = -1;  // and the most a collapse of the merge may cost (-1: any)
  double pilot_kept_per_inner = 0, pilot_kept_per_outline = 0;  // the vertices a piece keeps
  // at the bound per vertex, for those not beside a void and those beside one (Piece::outline)
  double pilot_forced_per_outline = 0;  // and those it keeps at any cost, per one beside a void
  // Peak resident memory of the process (Linux VmHWM, kB; 0 elsewhere) just before the merge:
  // what the pieces needed, without the kept-vertex triangulation.
  std::size_t peak_rss_before_merge_kb = 0;
  // Bytes the pieces' kept vertices, outline edges and tails took at that point: the whole-DEM
  // state, which grows with the kept count (the rest is bounded by the pieces in flight). qem:
  // the most its merge held at once (one group's pieces; all of them under dpts-mpi).
  std::size_t kept_bytes = 0;
  // qem: faces of the output not counter-clockwise in the output CRS (core::check_mesh's
  // clockwise_or_flat), counted as the merge writes them.
  std::size_t folded_faces = 0;
};

struct MetaResult {
  core::Tin tin;          // cells are raster cell indices (row-major), ascending
  std::vector<double> z;  // height of each kept cell
};

// Runs the whole method on band 1 of the DEM. Progress is reported (serialized) with stages
// "count", "values", "simplify", "merge"; returning false stops with dpts::Cancelled. Throws
// InputError when the DEM has no surface, IoError/InputError when a read fails.
MetaResult simplify_meta(const core::RasterSource& dem, const MetaOptions& options,
                         const core::Progress& progress, MetaStats* stats = nullptr);

// The piece engines' first stage: one streaming count of surface vertices per block (in
// strips of about tile_bytes / 4), then the k-d division into pieces that fit tile_bytes with
// `halo` cells of context (and hold at most max_vertices surface vertices, 0: any). Fills st's
// counts, block, count_s, target (from keep) and pieces.
// Throws InputError when the DEM has no valid cell or fewer than 3 surface vertices.
std::vector<core::Piece> divide_dem(const core::RasterSource& dem, const KeepTarget& keep,
                                    int levels, std::size_t tile_bytes, int halo,
                                    const core::Progress& progress, MetaStats& st,
                                    std::size_t max_vertices = 0);

// Pieces simplified at once: as many as there are threads, at most all of them.
std::size_t pieces_in_flight(std::size_t pieces);

// The working set of the pieces in flight at worst: the largest pieces_in_flight of their
// estimates (core::piece_bytes, each within tile_bytes), so a small DEM is not charged a
// whole tile per thread.
std::size_t pieces_in_flight_bytes(const std::vector<core::Piece>& pieces, int halo,
                                   std::size_t tile_bytes);

// Refuses (InputError naming the DEM, the target and both sizes) a run whose estimated need
// exceeds limit; limit 0: no check.
void check_memory(const core::RasterSource& dem, std::size_t target, std::size_t need,
                  std::size_t limit);

// The piece value of the paper's CalcPieceValue on a window of heights: the mean ED/GD over
// all pairs of `points` random points in the footprint (seeded), GD the straightened geodesics
// (pairwise_distances) on the Steiner graph of the grid TIN at dpts-eval's spacing on a DEM
// (kStraightenedDeltaFactorDem x its mean edge). Windows larger than max_cells are subsampled
// (every s-th row and column) to at most max_cells cells first: a tested cheaper equivalent (see
// tests/parallel/meta_test.cpp). col0, row0 place the window in the raster (for the frame).
// Returns 1 (flat) when the window has no face to sample.
double piece_value(const core::HeightGrid& window, int col0, int row0, const core::GridFrame& frame,
                   int points, int max_cells, std::uint64_t seed);

}  // namespace dpts::par

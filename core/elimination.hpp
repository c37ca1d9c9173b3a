// The elimination method (the DPTS paper, section 3.1) on a Delaunay TIN of a DEM:
// repeatedly remove the least important vertex by Delaunay removal and update the
// importance of the vertices whose star changed. Importance is VP (volume between the
// surfaces before and after the removal) or PLD (local distance preservation).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "core/grid.hpp"
#include "core/mesh.hpp"
#include "core/progress.hpp"

namespace dpts::core {

enum class Importance { vp, pld };
enum class VolumeMethod { exact, monte_carlo };

struct EliminationOptions {
  Importance importance = Importance::vp;
  VolumeMethod vp_volume = VolumeMethod::exact;  // exact: no noise, and faster (see README)
  int vp_samples = 100;                          // Monte Carlo points per VP evaluation
  std::uint64_t seed = 1;                        // Monte Carlo seed
  // Exact VP only: an importance is computed when its vertex could be the next removal, and
  // until then the queue holds a cheap lower bound of it (core::vp_volume_bound). The
  // removals, and so the TIN, are the same either way; off only to check that.
  bool lazy_vp = true;
  // A DEM with every cell valid: its Delaunay TIN made straight from the grid (each square
  // split along its Delaunay diagonal) instead of by CGAL's insertion. The TIN is the same
  // either way; off only to check that.
  bool grid_triangulation = true;
  // Whether the outline may run straight from cell a to cell b (both on one grid line, the
  // cells between them on the outline). Null: always (the frame is the output CRS up to an
  // affine map). For a reprojected DEM, a straight grid line bends in the output CRS, and the
  // caller limits how far the chord may stray from it. Called concurrently: must be thread-safe.
  std::function<bool(std::uint32_t cell_a, std::uint32_t cell_b)> outline_chord_ok;
  // Cells that are never removed (indexed by cell; empty: none): the context round a piece of
  // the meta method, and the piece's own outline cells next to its border.
  std::vector<std::uint8_t> pinned;
  // Where the vertices of this TIN are the only ones (grid units, cell centres at integers;
  // +-infinity where the DEM ends). A piece's TIN is later merged with the vertices its
  // neighbours keep beyond this box; an outline chord is accepted only if some circle through
  // its ends that is empty in this TIN also lies inside the box, so that the chord stays a
  // Delaunay edge of the merged TIN and the footprint stays exact. Null: no such limit.
  struct Box {
    double col_lo, col_hi, row_lo, row_hi;
  };
  std::optional<Box> chord_box;
};

// A directed outline edge of a TIN (cells), with the footprint on its left.
using OutlineEdge = std::array<std::uint32_t, 2>;

// One removal, as logged by Eliminator::eliminate(): the cell, and for an outline vertex the
// outline edges it joined, prev -> cell -> next, which the chord prev -> next replaced.
struct Removal {
  std::uint32_t cell = 0;
  bool outline = false;
  std::uint32_t prev = 0, next = 0;
};

// The simplified TIN is a core::Tin (mesh.hpp): counter-clockwise faces seen from above,
// rotated to start at their smallest index and sorted; every face lies in the DEM's valid
// footprint (footprint.hpp) and together they cover it exactly once.

// Simplifies the Delaunay TIN of one DEM by vertex elimination.
//
// The grid must outlive the Eliminator. Outline rule: a vertex on the outline of the valid
// footprint is removed only where the outline is straight through it (in grid space) and the
// straight outline edge is Delaunay afterwards, so the footprint never changes; corners of the
// DEM and of voids are never removed. Ties of importance are broken by cell index. The result
// is the same whatever the order in which compute_importance() ranges run.
class Eliminator {
 public:
  // Builds the Delaunay triangulation of the DEM's surface vertices (see footprint.hpp).
  // Throws std::invalid_argument when the DEM has no footprint triangle. progress (stage
  // "triangulate") is asked every 65536 insertions; false stops it with Cancelled.
  Eliminator(const HeightGrid& grid, const GridFrame& frame, const EliminationOptions& options,
             const Progress& progress = nullptr);
  ~Eliminator();
  Eliminator(const Eliminator&) = delete;
  Eliminator& operator=(const Eliminator&) = delete;

  // Number of surface vertices (the input vertex count) and of those still in the TIN.
  std::size_t vertex_count() const;
  std::size_t alive_count() const;

  // Computes the initial importance of surface vertices [begin, end). Reads shared state and
  // writes only those vertices' slots: safe to run concurrently on disjoint ranges.
  void compute_importance(std::size_t begin, std::size_t end);

  // Removes vertices, least important first, until `keep` remain or none can be removed
  // without changing the footprint. Requires compute_importance() on all vertices first. May
  // be called again with a smaller keep to go on; with `log`, appends each removal to it.
  // Throws dpts::Cancelled when progress returns false.
  void eliminate(std::size_t keep, const Progress& progress, std::vector<Removal>* log = nullptr);

  // The current TIN: faces inside the footprint only.
  Tin tin() const;

  // Surface cells (the vertex ids' cells, ascending) and whether each is still in the TIN.
  const std::vector<std::uint32_t>& cells() const;
  bool alive(std::size_t id) const;

  // The edges of the current TIN between a face inside the footprint and one outside it (or
  // the outside of the convex hull), directed with the inside face on the left.
  std::vector<OutlineEdge> outline_edges() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dpts::core

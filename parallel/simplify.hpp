// Simplification of a whole DEM held in memory, with oneTBB for the parallel stages.
#pragma once

#include <cstddef>
#include <optional>
#include <string_view>

#include "core/elimination.hpp"
#include "core/grid.hpp"

namespace dpts::par {

// The simplification methods (dpts-par --algo, the library's algo).
enum class Algorithm {
  vp,        // the paper's elimination with VP importance, whole DEM in memory
  pld,       // ... with PLD importance
  vp_meta,   // the paper's VP' piece engine (parallel/meta.hpp), out of core
  pld_meta,  // the paper's PLD'
  qslim,     // Garland-Heckbert quadric collapse (the paper's competitor), in memory
  qem,       // dpts's quadric collapse in its piece engine (parallel/qem_engine.hpp): default
};

// "vp", "pld", "vp-meta", "pld-meta", "qslim", "qem".
const char* name_of(Algorithm a);
// The method a name above names, or none.
std::optional<Algorithm> parse_algorithm(std::string_view name);
// The paper's meta method (VP', PLD').
inline bool is_meta(Algorithm a) { return a == Algorithm::vp_meta || a == Algorithm::pld_meta; }
// The importance of the elimination methods: PLD for pld and pld-meta, else VP.
inline core::Importance importance_of(Algorithm a) {
  return a == Algorithm::pld || a == Algorithm::pld_meta ? core::Importance::pld
                                                         : core::Importance::vp;
}

// The threads a run uses: `requested` when > 0, else every core oneTBB sees.
int thread_count(int requested);

// How many vertices to keep: a percentage of the input's surface vertices (P2L) or a count.
struct KeepTarget {
  std::optional<double> percent;        // in (0, 100]
  std::optional<std::size_t> vertices;  // >= 3
};

struct SimplifyStats {
  std::size_t input_vertices = 0;   // surface vertices of the DEM
  std::size_t target_vertices = 0;  // what the keep target asks for
  std::size_t kept_vertices = 0;    // may exceed target when the outline needs more
  double triangulate_s = 0, importance_s = 0, simplify_s = 0;
};

// Number of vertices a target keeps out of `input` (rounded, at least 3, at most input).
std::size_t target_count(const KeepTarget& target, std::size_t input);

// Builds the Delaunay TIN of the DEM, computes the initial importance of all vertices in
// parallel (oneTBB tasks over vertex ranges; the result does not depend on the thread count),
// then eliminates vertices down to the target. Progress is reported from serial stages.
core::Tin simplify_dem(const core::HeightGrid& grid, const core::GridFrame& frame,
                       const core::EliminationOptions& options, const KeepTarget& target,
                       const core::Progress& progress, SimplifyStats* stats = nullptr);

}  // namespace dpts::par

// The distance-preserving error of a simplified TIN (the DPTS paper, sections 2 and 5.3),
// with geodesics on the Steiner graph computed by parallel Dijkstra queries (oneTBB).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/progress.hpp"
#include "core/steiner_graph.hpp"
#include "parallel/pair_routes.hpp"

namespace dpts::par {

// How pairwise_distances measures the pairs.
enum class PairwiseMethod {
  // Each pair by one Dijkstra from the endpoint that ranks the other nearer, stopping when its
  // targets are settled (each query searches about three quarters of the graph).
  kOneWay,
  // Meeting in the middle: every source searched once, to a radius fitted so that for each
  // pair the two radii overlap (estimated from two full searches); a pair is the least sum of
  // both searches' distances over the outer shell of one of them (straightened: the path
  // through that node, the earlier search's part told by the nodes it bends at). Pairs the
  // radii turn out too short for are measured one way. About a third of the graph per query.
  kMeet,
};

// How pairwise_distances works, and whom it tells of its progress.
struct PairwiseOptions {
  PairwiseMethod method = PairwiseMethod::kMeet;
  // Each pair searched with straight segments across faces (GeodesicQuery::set_anchored),
  // then its path pulled taut into a locally shortest geodesic (core::PathStraightener):
  // exact but for the rare pair whose search still took the longer of two routes nearly equal
  // in length (so meeting, up to 2 meeting nodes apart are tried for each pair, and one way,
  // the paths from both ends where both searches reach the other). false: the paper's Steiner
  // distances, a few tenths of a percent to several percent long depending on delta.
  bool straighten = true;
  // With straighten: each pair's straightened path into routes_out (origin: the first point),
  // for shorten_along on another mesh of the same points.
  PairRoutes* routes_out = nullptr;
  // At most this many queries (each with its labels for every node) exist at once, fewer
  // threads working if need be (0: no bound; at least min_searches(method) must be allowed);
  // the figures do not depend on it.
  std::size_t max_searches = 0;
  // The same pairs' distances on another surface of the same points (estimate[a * K + b],
  // a < b, as pairwise_distances gives them; dpts-eval gives both meshes' straightened searches
  // the paper's Steiner distances on T', and with --steiner T's searches those of T'), if
  // known and all finite: the meeting searches' radii are then scaled from these, with no
  // pilots searched in full, instead of from straight-line distances, so each search stops
  // nearer where its pairs need it to. A wrong estimate costs time, not exactness: a pair the
  // radii miss is searched one way. (Where two routes of a pair are nearly equal in length,
  // which one a straightened search finds may depend on where its searches meet.)
  const std::vector<double>* estimate = nullptr;
  // If given, called as each source's search finishes with the number of sources searched so
  // far (1 to K; the few pairs left to one-way queries after meeting are not counted). Calls
  // are serialized but come from any worker thread.
  std::function<void(std::size_t searched)> on_search;
};

// What the queries of pairwise_distances did.
struct PairwiseStats {
  double settled = 0;             // graph nodes settled, all queries together
  std::size_t one_way_pairs = 0;  // pairs measured one way
  // Straightening: paths straightened, the strip passes and reroutes around vertices they
  // took, and paths that could not be (a degenerate face: their Steiner length is kept).
  std::size_t straightened = 0, straighten_passes = 0, reroutes = 0, straighten_failed = 0;
};

// Geodesic distances between all pairs of points on the graph's mesh: out[i * K + j] for
// i < j (the rest 0). Sequential Dijkstra queries spread over oneTBB tasks, scratch per
// thread: the figures are the same for any thread count. If `stats` is given, what the
// queries did is added to it.
std::vector<double> pairwise_distances(const core::SteinerGraph& graph,
                                       const std::vector<core::SurfacePoint>& points,
                                       const PairwiseOptions& options = {},
                                       PairwiseStats* stats = nullptr);
// Each pair's distance (distances[a * K + b], a < b, as pairwise_distances gives them) lowered
// to its length along the pair's route in `routes` (found on another mesh of the same points:
// PathStraightener::along its bends and PathStraightener::follow its taut points, the shorter)
// where that is shorter, beyond rounding; returns how many were. Where the search on one mesh
// took the longer of two near-equal routes, the other's mostly did not.
// In parallel; the same figures for any thread count. With shortened_routes (reset by the
// caller for these points), each pair shortened is given the route of its new path there, for
// the other mesh to try in turn.
std::size_t shorten_along(const core::SteinerGraph& graph,
                          const std::vector<core::SurfacePoint>& points, const PairRoutes& routes,
                          std::vector<double>& distances, PairRoutes* shortened_routes = nullptr);
// The pairs' arrays of a run of `sets` sets of k points, in bytes (in doubles: any k): every
// set's distances on both meshes (and, straightened, the guess and the indexes of the routes
// held at once: on both meshes, and the pairs shortened on one), and a stage's own (its
// candidates' lengths and routes, the pairs left one way, the ride-along distances).
// evaluate_distances counts them in its memory budget (EvalResult::pairs_bytes).
double pair_array_bytes(double k, double sets, bool straightened);
// The fewest queries pairwise_distances needs at once: 2 when meeting in the middle (one
// searching while a finished one waits for its joins), 1 one way.
inline std::size_t min_searches(PairwiseMethod method) {
  return method == PairwiseMethod::kMeet ? 2 : 1;
}

struct EvalOptions {
  int points = 100;  // K points per set
  int sets = 3;      // independent sets
  std::uint64_t seed = 1;
  // Steiner spacing on both meshes; 0: kStraightenedDeltaFactorDem x the mean edge of T, and
  // kStraightenedDeltaFactor x that of T' but never less than T's (straighten);
  // kDefaultDeltaFactor x the mean edge of T on both (the paper's distances).
  double delta_m = 0;
  // Points outside T' (and given points outside T) within this distance are snapped onto it.
  double snap_m = 0;
  // Each pair's Steiner paths straightened into geodesics (PairwiseOptions::straighten), and
  // its route on either mesh straightened on the other (shorten_along): near exact, measured
  // one way. false: the paper's Steiner distances, searched by `method`.
  bool straighten = true;
  PairwiseMethod method = PairwiseMethod::kMeet;
  // Memory the geodesics may use (Steiner graphs and searches), 0: no bound. More threads than
  // fit work fewer at a time; a run that does not fit with one is refused before the graphs
  // are built (InputError). Not used with `exact` (its memory is not bounded).
  std::size_t memory_budget_bytes = 0;
  // The reference: exact geodesics (CGAL's Surface_mesh_shortest_path, one propagation per
  // source, see core/exact_geodesic.hpp) instead of the Steiner graph; delta_m, method and
  // memory_budget_bytes are not used. For small meshes: 0.75 s and 250 MB per source on a
  // 100 x 100 grid TIN, one source per thread at once.
  bool exact = false;
  // Given sample points instead of random ones: sample_xy[s][i] is point i of set s (x, y in
  // the meshes' CRS; every set at least 2 points). points, sets and seed are then not used.
  std::vector<std::vector<std::array<double, 2>>> sample_xy;
  // Keep every pair's two distances in EvalResult::pairs.
  bool keep_pairs = false;
};

// Default Steiner spacing as a fraction of the mean 3D edge length of the original TIN: the
// paper's Steiner distances (and the meta method's piece values).
inline constexpr double kDefaultDeltaFactor = 0.25;
// Default spacing of straightened geodesics on T', as a fraction of its own mean edge. The
// search only has to find the shortest route among near ties, the straightening makes its
// length exact: against exact geodesics on st_helens_crater, zion_canyon and peru_mongon
// (every mode at 10 % and 50 %) the measure stays within 3 % at 0.35, 1.5 x faster per node
// than at 0.25; at 0.5 it moves by up to 5 %.
inline constexpr double kStraightenedDeltaFactor = 0.35;
// The same for T, the DEM's grid TIN, coarser: its faces are all alike (half cells), and 0.5
// puts one point inside each side of a square cell and two inside its diagonal, 1.6 x fewer
// nodes than 0.35 and about twice as fast. Alone, it let the search take the longer route of a
// near tie more often (mean error on T 5.3e-6 of exact instead of 1.8e-6 on peru_mongon, the
// measure of its 50 % qslim mesh 6.9 % high); with each pair also pulled taut along its route
// on T' (shorten_along) the error is 1.4e-6 and the measure within 1.6 % of exact on three DEMs,
// every mode at 10 and 50 % (README, "Evaluator accuracy"). At 0.7 (one point inside every
// edge) the measure of a 50 % mesh of st_helens_crater moved by 8.6 % (without the routes).
inline constexpr double kStraightenedDeltaFactorDem = 0.5;

struct EvalResult {
  double distance_error = 0;             // mean of the set errors
  std::vector<double> set_errors;        // per set: mean |GD_T - GD_T'| / GD_T over all pairs
  double delta_m = 0, delta_mesh_m = 0;  // Steiner spacing on T and on T'
  std::size_t original_nodes = 0, simplified_nodes = 0;  // Steiner graph sizes
  std::size_t snapped = 0;                               // sample points snapped onto T'
  double original_s = 0, simplified_s = 0;  // wall time of the geodesics on T and on T'
  // Mean share of the graph one Dijkstra query settled, on T and on T'.
  double original_searched = 0, simplified_searched = 0;
  // Pairs measured one way (all of them with kOneWay; with kMeet those the radii missed).
  std::size_t original_one_way = 0, simplified_one_way = 0;
  // Estimated memory of the geodesics: the larger graph (they are built one at a time), one
  // search on it; and how many searches the memory budget let exist at once (0: no bound). All
  // 0 with exact geodesics.
  std::size_t graphs_bytes = 0, search_bytes = 0, max_searches = 0;
  // Memory of the pairs' arrays (their distances on both meshes, every set's), and,
  // straightened, of the routes kept for the other mesh (PairRoutes) in memory (the rest in a
  // temporary file). Both counted in the budget.
  std::size_t pairs_bytes = 0, routes_bytes = 0;
  bool exact = false;  // the geodesics were exact (EvalOptions::exact)
  // Steiner paths straightened (EvalOptions::straighten), on T and on T' together: the paths,
  // and those that could not be (a degenerate face: their Steiner length kept); the strips
  // pulled taut (one per pass) and the vertices rerouted around.
  std::size_t straightened = 0, straighten_failed = 0, straighten_passes = 0, reroutes = 0;
  // Pair distances shortened along the other mesh's route (shorten_along), T and T' together,
  // once for each round that shortened one.
  std::size_t shortened = 0;
  // Pairs, all sets together: measured (in the set errors); not connected on T (a DEM whose
  // valid cells form islands: no distance to compare, left out of the mean); and at distance 0
  // on T (a point given twice: no relative error, left out).
  std::size_t pairs_measured = 0, pairs_unconnected = 0, pairs_coincident = 0;
  // With EvalOptions::keep_pairs: every pair i < j of every set, in order of (set, i, j), sets
  // numbered from 0; distances +infinity where not connected.
  struct Pair {
    std::uint32_t set = 0, i = 0, j = 0;
    double on_t = 0, on_s = 0;
  };
  std::vector<Pair> pairs;
};

// Samples K points uniformly in T's footprint per set (seeded by seed and set), or takes the
// given sample_xy, lifts them onto T and T', and compares all pairwise geodesics. Never
// silently wrong: throws InputError, with a count, when sample points fall outside T' or (given
// ones) outside T, farther than snap_m; when pairs connected on T are not connected on T' (a
// mesh in parts, or slit); and when a set has no pair to measure. Pairs not connected on T are
// left out of the mean and counted (pairs_unconnected). With `exact`, throws InputError when T
// cannot be given to CGAL, and std::invalid_argument naming the face or vertex when T' cannot
// (see ExactGeodesics); without, std::invalid_argument when T' is no proper surface for the
// Steiner graph (an edge of three faces).
// `progress`, if given, is called with a one-line description of each stage as it starts
// (graphs built, each set's geodesics on T and on T'), fraction 0, from the serial points
// between them; and in the geodesic stages as each search finishes, with the fraction of the
// sources searched (serialized, from worker threads). Returning false stops the run with
// dpts::Cancelled (at the end of the stage when returned during one).
EvalResult evaluate_distances(const core::TriMesh& original, const core::TriMesh& simplified,
                              const EvalOptions& options, const core::Progress& progress = nullptr);

}  // namespace dpts::par

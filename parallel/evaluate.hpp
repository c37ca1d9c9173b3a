// The distance-preserving error of a simplified TIN (the DPTS paper, sections 2 and 5.3),
// with geodesics on the Steiner graph computed by parallel Dijkstra queries (oneTBB).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/steiner_graph.hpp"

namespace dpts::par {

// How pairwise_distances measures the pairs.
enum class PairwiseMethod {
  // Each pair by one Dijkstra from the endpoint that ranks the other nearer, stopping when its
  // targets are settled (each query searches about three quarters of the graph).
  kOneWay,
  // Meeting in the middle: every source searched once, to a radius fitted so that for each
  // pair the two radii overlap (estimated from two full searches); a pair is the least sum of
  // both searches' distances over the outer shell of one of them. Pairs the radii turn out too
  // short for are measured one way. About a third of the graph per query.
  kMeet,
};

// How pairwise_distances works, and whom it tells of its progress.
struct PairwiseOptions {
  PairwiseMethod method = PairwiseMethod::kMeet;
  // At most this many queries (each with its labels for every node) exist at once, fewer
  // threads working if need be (0: no bound; at least min_searches(method) must be allowed);
  // the figures do not depend on it.
  std::size_t max_searches = 0;
  // If given, called as each source's search finishes with the number of sources searched so
  // far (1 to K; the few pairs left to one-way queries after meeting are not counted). Calls
  // are serialized but come from any worker thread.
  std::function<void(std::size_t searched)> on_search;
};

// What the queries of pairwise_distances did.
struct PairwiseStats {
  double settled = 0;             // graph nodes settled, all queries together
  std::size_t one_way_pairs = 0;  // pairs measured one way
};

// Geodesic distances between all pairs of points on the graph's mesh: out[i * K + j] for
// i < j (the rest 0). Sequential Dijkstra queries spread over oneTBB tasks, scratch per
// thread: the figures are the same for any thread count. If `stats` is given, what the
// queries did is added to it.
std::vector<double> pairwise_distances(const core::SteinerGraph& graph,
                                       const std::vector<core::SurfacePoint>& points,
                                       const PairwiseOptions& options = {},
                                       PairwiseStats* stats = nullptr);
// The fewest queries pairwise_distances needs at once: 2 when meeting in the middle (one
// searching while a finished one waits for its joins), 1 one way.
inline std::size_t min_searches(PairwiseMethod method) {
  return method == PairwiseMethod::kMeet ? 2 : 1;
}

struct EvalOptions {
  int points = 100;  // K points per set
  int sets = 3;      // independent sets
  std::uint64_t seed = 1;
  double delta_m = 0;  // Steiner spacing; 0: kDefaultDeltaFactor x mean edge of T
  double snap_m = 0;   // points outside T' within this distance are snapped onto it
  PairwiseMethod method = PairwiseMethod::kMeet;
  // Memory the geodesics may use (Steiner graphs and searches), 0: no bound. More threads than
  // fit work fewer at a time; a run that does not fit with one is refused before the graphs
  // are built (InputError).
  std::size_t memory_budget_bytes = 0;
};

// Default Steiner spacing as a fraction of the mean 3D edge length of the original TIN.
inline constexpr double kDefaultDeltaFactor = 0.25;

struct EvalResult {
  double distance_error = 0;       // mean of the set errors
  std::vector<double> set_errors;  // per set: mean |GD_T - GD_T'| / GD_T over all pairs
  double delta_m = 0;
  std::size_t original_nodes = 0, simplified_nodes = 0;  // Steiner graph sizes
  std::size_t snapped = 0;                               // sample points snapped onto T'
  double original_s = 0, simplified_s = 0;  // wall time of the geodesics on T and on T'
  // Mean share of the graph one Dijkstra query settled, on T and on T'.
  double original_searched = 0, simplified_searched = 0;
  // Pairs measured one way (all of them with kOneWay; with kMeet those the radii missed).
  std::size_t original_one_way = 0, simplified_one_way = 0;
  // Estimated memory of the geodesics: the two graphs, one search on T; and how many searches
  // the memory budget let exist at once (0: no bound).
  std::size_t graphs_bytes = 0, search_bytes = 0, max_searches = 0;
};

// Samples K points uniformly in T's footprint per set (seeded by seed and set), lifts them onto
// T and T', and compares all pairwise geodesics. Throws InputError when sample points fall
// outside T' (farther than snap_m), with their count.
// `progress`, if given, is called with a one-line description of each stage as it starts
// (graphs built, each set's geodesics on T and on T'), fraction 0, from the serial points
// between them; and in the geodesic stages as each search finishes, with the fraction of the
// sources searched (serialized, from worker threads). Returning false stops the run with
// dpts::Cancelled (at the end of the stage when returned during one).
using StageProgress = std::function<bool(const std::string& stage, double fraction)>;
EvalResult evaluate_distances(const core::TriMesh& original, const core::TriMesh& simplified,
                              const EvalOptions& options, const StageProgress& progress = nullptr);

}  // namespace dpts::par

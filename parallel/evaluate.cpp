// Parallel geodesic queries and the distance-preserving error.
#include "parallel/evaluate.hpp"

#include <tbb/concurrent_queue.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/errors.hpp"
#include "core/exact_geodesic.hpp"
#include "core/geodesic_path.hpp"
#include "core/surface_sampling.hpp"
#include "parallel/exact_pairwise.hpp"
#include "parallel/memory.hpp"

namespace dpts::par {

namespace {

using Shell = std::vector<std::pair<std::uint32_t, double>>;

// Straightened meeting (meet_straightened): the most meeting nodes whose routes are pulled taut
// for one pair, and how much longer than the best one's their sum may be.
// note: 2, not 4: against exact geodesics (3 DEMs, every mode at 10 and 50 %, 780 pairs each)
// the measure's diff moved by 0.6 % at most (peru_mongon vp 50 %: +0.28 to +0.87 %; the worst,
// zion_canyon qslim 50 %, +1.47 to +1.42 %), and San Gabriel's geodesics took 2-9 % less time.
constexpr std::size_t kMeetingRoutes = 2;
constexpr double kNearTie = 0.01;
// The meeting searches' pilots, searched in full: their largest ratio of geodesic to
// straight-line distance scales the radii. None where the pairs' distances on another surface
// are given (PairwiseOptions::estimate): the radii then scale those, by kEstimateMargin.
// note: a fixed count of pilots, not one per thread: the radii, and so the figures, must not
// depend on the thread count.
constexpr std::size_t kPilots = 2;
// note: with dpts-eval's guess (the paper's Steiner distances on T', a little long) no pair of
// T was left to one-way searches on San Gabriel's 10 % and 1 % meshes; a pair the radii miss
// is searched one way (slower, as exact).
constexpr double kEstimateMargin = 1.02;
// The most memory the routes kept for the other mesh (PairRoutes) take, all sets together, their
// index apart; the rest go to a temporary file.
// note: each pair's candidates (up to 3) stored: a set of 100 points on San Gabriel (770k
// cells) stores about 11 MB of routes on T and 6 MB on its 10 % mesh; they grow with the
// square of the points.
constexpr std::size_t kRoutesMemory = std::size_t{8} << 20;
// The most rounds of routes tried on the other mesh after both meshes' searches (see
// evaluate_distances): the first, T's on T', always; each later one only while the last
// shortened some pair.
constexpr int kRouteRounds = 4;

// Squared straight-line (3D) distance between points i and j.
double straight2(const std::vector<core::SurfacePoint>& points, std::size_t i, std::size_t j) {
  const double dx = points[i].x - points[j].x, dy = points[i].y - points[j].y,
               dz = points[i].z - points[j].z;
  return dx * dx + dy * dy + dz * dz;
}

// routes reset for the pairs of `points`, their offsets from the first point.
void reset_routes(PairRoutes& routes, const std::vector<core::SurfacePoint>& points) {
  routes.reset(points.size(),
               {points.empty() ? 0.0 : points[0].x, points.empty() ? 0.0 : points[0].y});
}

// Path i -> j's route (route) stored in routes for the pair min(i, j) < max(i, j).
PairRoutes::Id add_route(PairRoutes& routes, const std::vector<core::SurfacePoint>& points,
                         std::size_t i, std::size_t j, const core::PathRoute& route) {
  const core::SurfacePoint& end = points[std::max(i, j)];
  return routes.add(route, i > j, {end.x, end.y});
}

// Every point but point i, in order.
std::vector<core::SurfacePoint> others(const std::vector<core::SurfacePoint>& points,
                                       std::size_t i) {
  std::vector<core::SurfacePoint> t;
  for (std::size_t j = 0; j < points.size(); ++j) {
    if (j != i) t.push_back(points[j]);
  }
  return t;
}

// A pilot's estimate for the meeting radii from its full search (d: its distances to the
// others, in order): the largest ratio of geodesic to straight-line distance over the farther
// half of its pairs (1 at least).
double pilot_ratio(const std::vector<core::SurfacePoint>& points, std::size_t p,
                   const std::vector<double>& d) {
  std::vector<std::pair<double, double>> far;  // (straight, geodesic)
  for (std::size_t j = 0, t = 0; j < points.size(); ++j) {
    if (j != p) far.emplace_back(std::sqrt(straight2(points, p, j)), d[t++]);
  }
  std::sort(far.begin(), far.end());
  double ratio = 1.0;
  for (std::size_t t = far.size() / 2; t < far.size(); ++t) {
    if (far[t].first > 0 && std::isfinite(far[t].second)) {
      ratio = std::max(ratio, far[t].second / far[t].first);
    }
  }
  return ratio;
}

// The needed pairs i < j (need[i * K + j]) shared out to the sources: each to the endpoint that
// ranks the other nearer (straight-line distance; ties to i), so that every search stops at
// about its nearest half of the points.
std::vector<std::vector<std::size_t>> assign_pairs(const std::vector<core::SurfacePoint>& points,
                                                   const std::vector<char>& need) {
  const std::size_t k = points.size();
  auto d2 = [&](std::size_t i, std::size_t j) { return straight2(points, i, j); };
  std::vector<std::vector<std::size_t>> rank(k, std::vector<std::size_t>(k, 0));
  for (std::size_t i = 0; i < k; ++i) {
    std::vector<std::size_t> order;
    for (std::size_t j = 0; j < k; ++j) {
      if (j != i) order.push_back(j);
    }
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      const double da = d2(i, a), db = d2(i, b);
      return da < db || (da == db && a < b);
    });
    for (std::size_t r = 0; r < order.size(); ++r) rank[i][order[r]] = r;
  }
  std::vector<std::vector<std::size_t>> assigned(k);
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = i + 1; j < k; ++j) {
      if (!need[i * k + j]) continue;
      if (rank[i][j] <= rank[j][i]) {
        assigned[i].push_back(j);
      } else {
        assigned[j].push_back(i);
      }
    }
  }
  return assigned;
}

// Measures the pairs i < j with need[i * K + j] into out[i * K + j]: each pair by a Dijkstra
// from the endpoint that ranks the other nearer (straight-line distance), so that every query
// stops at about its nearest half of the points instead of the farthest; with `straighten`,
// each pair's path is then pulled taut (the shorter length kept). Adds what the queries did to
// `stats`; calls searched (if given) as each source is done.
void measure_one_way(const core::SteinerGraph& graph, const std::vector<core::SurfacePoint>& points,
                     const std::vector<char>& need, bool straighten, std::vector<double>& out,
                     PairwiseStats& stats, const std::function<void()>& searched,
                     PairRoutes* routes_out = nullptr) {
  const std::size_t k = points.size();
  // note: routes only with straighten (they are the straightened paths' bends).
  if (!straighten) routes_out = nullptr;
  std::vector<PairRoutes::Id> reverse_routes(routes_out ? k * k : 0, PairRoutes::kNone);
  const std::vector<std::vector<std::size_t>> assigned = assign_pairs(points, need);
  // note: two searches, each straightened, rank the routes of a pair independently; where the
  // graph's error put one on the longer of two nearly equal routes, the other mostly is not.
  // So with `straighten`, a source also measures the pairs assigned to the other end that its
  // search settles anyway (into reverse[i * K + j]), and each pair takes the shorter.
  std::vector<std::vector<std::size_t>> rides(k);
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j : assigned[i]) rides[j].push_back(i);
  }
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> reverse(straighten ? k * k : 0, inf);
  // Per source: the same sums for any thread count.
  std::vector<std::size_t> settled_by(k, 0);
  std::vector<core::PathStraightener::Stats> straightened_by(k);
  struct Scratch {
    core::GeodesicQuery query;
    core::PathStraightener straightener;
    Scratch(const core::SteinerGraph& g, bool anchored) : query(g), straightener(g) {
      query.set_anchored(anchored);
    }
  };
  tbb::enumerable_thread_specific<std::unique_ptr<Scratch>> scratch;
  // note: grain 1: query costs differ a lot; let the scheduler balance them.
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, k, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        auto& sc = scratch.local();
        if (!sc) sc = std::make_unique<Scratch>(graph, straighten);
        std::vector<core::SurfacePoint> targets;
        std::vector<double> d;
        core::PathRoute best;
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          if (assigned[i].empty()) {
            if (searched) searched();
            continue;
          }
          // The other needed pairs of i ride along: those the search settles
          // before its own are done get a second path, from this side.
          targets.clear();
          for (std::size_t j : assigned[i]) targets.push_back(points[j]);
          const std::size_t own = targets.size();
          if (straighten) {
            for (std::size_t j : rides[i]) targets.push_back(points[j]);
          }
          sc->query.distances(points[i], targets, d, own);
          settled_by[i] = sc->query.settled();
          const auto before = sc->straightener.stats();
          for (std::size_t t = 0; t < targets.size(); ++t) {
            const std::size_t j = t < own ? assigned[i][t] : rides[i][t - own];
            if (straighten) {
              d[t] = sc->straightener.shortest(sc->query, points[i], t, targets[t], d[t],
                                               routes_out ? &best : nullptr);
              if (routes_out && std::isfinite(d[t])) {
                const PairRoutes::Id id = add_route(*routes_out, points, i, j, best);
                if (t < own) {
                  routes_out->assign(std::min(i, j), std::max(i, j), id);
                } else {
                  reverse_routes[i * k + j] = id;
                }
              }
            }
            if (t < own) {
              out[std::min(i, j) * k + std::max(i, j)] = d[t];
            } else {
              reverse[i * k + j] = d[t];
            }
          }
          const auto& after = sc->straightener.stats();
          straightened_by[i] = {after.paths - before.paths, after.passes - before.passes,
                                after.reroutes - before.reroutes, after.failed - before.failed};
          if (searched) searched();
        }
      });
  if (straighten) {
    for (std::size_t i = 0; i < k; ++i) {
      for (std::size_t j : rides[i]) {
        double& v = out[std::min(i, j) * k + std::max(i, j)];
        if (reverse[i * k + j] < v) {
          v = reverse[i * k + j];
          if (routes_out)
            routes_out->assign(std::min(i, j), std::max(i, j), reverse_routes[i * k + j]);
        }
      }
    }
  }
  for (std::size_t i = 0; i < k; ++i) {
    stats.settled += static_cast<double>(settled_by[i]);
    stats.straightened += straightened_by[i].paths;
    stats.straighten_passes += straightened_by[i].passes;
    stats.reroutes += straightened_by[i].reroutes;
    stats.straighten_failed += straightened_by[i].failed;
  }
}

// The estimate if it gives every pair a < b of k points a positive finite distance, else none
// (the radii then scale straight-line distances).
const std::vector<double>* usable_estimate(const std::vector<double>* estimate, std::size_t k) {
  if (!estimate || estimate->size() != k * k) return nullptr;
  for (std::size_t a = 0; a < k; ++a) {
    for (std::size_t b = a + 1; b < k; ++b) {
      const double e = (*estimate)[a * k + b];
      if (!(e > 0) || !std::isfinite(e)) return nullptr;
    }
  }
  return estimate;
}

// Search radii for meeting in the middle: R_i + R_j >= c_ij for every pair, with the sum of
// squared radii (about the area searched) made small by coordinate descent. Deterministic.
std::vector<double> meeting_radii(const std::vector<double>& c, std::size_t k) {
  std::vector<double> r(k, 0.0);
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = 0; j < k; ++j) {
      if (j != i) r[i] = std::max(r[i], c[i * k + j] / 2);
    }
  }
  for (int round = 0; round < 50; ++round) {
    for (std::size_t i = 0; i < k; ++i) {
      double need = 0.0;
      for (std::size_t j = 0; j < k; ++j) {
        if (j != i) need = std::max(need, c[i * k + j] - r[j]);
      }
      r[i] = need;
    }
  }
  return r;
}

// The most searches pairwise_distances holds at once with no bound given: besides one per
// thread, up to two more each, waiting for their joins, so that a thread rarely idles; but
// straightened, one per thread (each holds 36 bytes a node, not 16: the memory is the limit;
// smallest radius first, a search rarely ends before the one started before it).
std::size_t unbounded_searches(std::size_t threads, bool straighten) {
  return straighten ? std::max<std::size_t>(threads, 2) : 3 * threads - 1;
}

// The first `pilots` points searched in full (in parallel), their distances into direct and
// their searches' sizes into settled_by: the estimate the meeting radii need, the largest ratio
// of geodesic to straight-line distance over the farther half of each one's pairs.
double search_pilots(const core::SteinerGraph& graph, const std::vector<core::SurfacePoint>& points,
                     std::size_t pilots, std::vector<double>& direct,
                     std::vector<std::size_t>& settled_by, const std::function<void()>& searched) {
  const std::size_t k = points.size();
  std::vector<double> ratios(pilots, 1.0);
  tbb::parallel_for(std::size_t{0}, pilots, [&](std::size_t p) {
    core::GeodesicQuery q(graph);
    std::vector<double> d;
    q.distances(points[p], others(points, p), d);
    settled_by[p] = q.settled();
    for (std::size_t j = 0, t = 0; j < k; ++j) {
      if (j != p) direct[p * k + j] = d[t++];
    }
    ratios[p] = pilot_ratio(points, p, d);
    if (searched) searched();
  });
  return ratios.empty() ? 1.0 : *std::max_element(ratios.begin(), ratios.end());
}

// The radius each non-pilot point is searched to (meeting_radii), from the pilots' ratio of
// geodesic to straight-line distance, or from the pairs' estimated distances where given
// (usable_estimate: then no pilots), and the longest segment w; the pilots' are unused.
std::vector<double> search_radii(const std::vector<core::SurfacePoint>& points,
                                 const std::vector<double>* estimate, std::size_t pilots,
                                 double ratio, double w) {
  const std::size_t k = points.size();
  std::vector<double> c(k * k, 0.0);
  for (std::size_t i = pilots; i < k; ++i) {
    for (std::size_t j = pilots; j < k; ++j) {
      if (j == i) continue;
      const double straight = std::sqrt(straight2(points, i, j));
      // note: a geodesic is never shorter than the straight line.
      c[i * k + j] =
          (estimate ? std::max(kEstimateMargin * (*estimate)[std::min(i, j) * k + std::max(i, j)],
                               straight)
                    : 1.05 * ratio * straight) +
          w;
    }
  }
  return meeting_radii(c, k);
}

// Each pair a < b's distance into out: from either one's search where it settled the other,
// else their join where it proves itself exact (within both radii less the longest segment
// w); the pairs neither gives are marked in left, and counted.
// note: every value comes from searches and joins whose results do not depend on the thread
// count, chosen by a fixed rule, so the figures are the same for any --threads.
std::size_t settle_pairs(const std::vector<double>& direct, const std::vector<double>& meet,
                         const std::vector<double>& radius, double w, std::size_t pilots,
                         std::size_t k, std::vector<double>& out, std::vector<char>& left) {
  const double inf = std::numeric_limits<double>::infinity();
  std::size_t left_count = 0;
  for (std::size_t a = 0; a < k; ++a) {
    for (std::size_t b = a + 1; b < k; ++b) {
      double v = direct[a * k + b];
      if (!(v < inf)) v = direct[b * k + a];
      if (!(v < inf) && a >= pilots && meet[a * k + b] <= radius[a] + radius[b] - w) {
        v = meet[a * k + b];
      }
      if (v < inf) {
        out[a * k + b] = v;
      } else {
        left[a * k + b] = 1;
        ++left_count;
      }
    }
  }
  return left_count;
}

// Where a source's search ended, for straightened meeting: its settled nodes within the
// longest segment of its radius (its shell), each with its distance and the node its path last
// bent at (GeodesicQuery::bend), by node; and the bends of those paths, each with the bend
// before it, by node. So each shell node's path from the source is told by its bends alone,
// after the search's labels are gone.
struct Half {
  // note: the distance as a float (12 bytes a node): it only ranks the meeting nodes, whose
  // paths are then pulled taut.
  struct Node {
    std::uint32_t node, bend;
    float d;
  };
  std::vector<Node> shell;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> bends;

  Half() = default;
  // The half of the search q (over a graph of `nodes` nodes) has just done: the nodes of its
  // outer shell that `keep` (a later search may reach them).
  template <typename Keep>
  Half(const core::GeodesicQuery& q, std::size_t nodes, const Shell& outer, Keep&& keep) {
    for (const auto& [v, d] : outer) {
      if (keep(v)) shell.push_back({v, q.bend(v), static_cast<float>(d)});
    }
    shell.shrink_to_fit();
    // note: by node, so that the joins read the later search's labels in address order.
    std::sort(shell.begin(), shell.end(),
              [](const Node& a, const Node& b) { return a.node < b.node; });
    // note: the paths share their first bends: each path is followed until a bend seen
    // already (marked in a bitmap over the nodes, per thread, cleared after).
    thread_local std::vector<std::uint64_t> seen;
    if (seen.size() < nodes / 64 + 1) seen.assign(nodes / 64 + 1, 0);
    auto mark = [&](std::uint32_t b) {
      std::uint64_t& word = seen[b >> 6];
      const std::uint64_t bit = std::uint64_t{1} << (b & 63);
      const bool was = word & bit;
      word |= bit;
      return !was;
    };
    for (const Node& n : shell) {
      for (std::uint32_t b = n.bend; b != core::LabelHeap::kNone && mark(b); b = q.bend(b)) {
        bends.emplace_back(b, q.bend(b));
      }
    }
    for (const auto& b : bends) seen[b.first >> 6] = 0;
    std::sort(bends.begin(), bends.end());
    bends.shrink_to_fit();
  }

  // The bends of shell node t's path, from the source's end, into out (cleared).
  void path_bends(std::size_t t, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (std::uint32_t b = shell[t].bend; b != core::LabelHeap::kNone;) {
      out.push_back(b);
      const auto it = std::lower_bound(bends.begin(), bends.end(),
                                       std::pair<std::uint32_t, std::uint32_t>{b, 0});
      b = it != bends.end() && it->first == b ? it->second : core::LabelHeap::kNone;
    }
    std::reverse(out.begin(), out.end());
  }
};

// Straightened pairs meeting in the middle (PairwiseMethod::kMeet with straighten): the same
// radii as pairwise_in_arena's, with anchored searches. A pair one search settles is
// straightened on its labels (PathStraightener::shortest; both ways where both do). A pair
// the two searches meet on is joined as there, then its path is pulled taut along the route
// through the meeting node: the earlier search's part told by its bends (Half), the later's
// node by node; and along the best meeting node at least a few segments away from it, if
// nearly as short (where two routes around a hill are nearly equal, the graph's error may
// rank the longer first). The shortest is kept. Pairs left are measured one way.
std::vector<double> meet_straightened(const core::SteinerGraph& graph,
                                      const std::vector<core::SurfacePoint>& points,
                                      const std::vector<double>* estimate, PairRoutes* routes_out,
                                      PairwiseStats& stats, std::size_t tokens,
                                      const std::function<void()>& searched) {
  const std::size_t k = points.size();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> out(k * k, 0.0);
  // Each pair's candidates: straightened from i's search (i * k + j), and joined (a < b).
  std::vector<double> direct(k * k, inf), direct_len(k * k, inf), joined_len(k * k, inf);
  // note: their routes stored as found, each pair given its best at the end.
  std::vector<PairRoutes::Id> direct_route(routes_out ? k * k : 0, PairRoutes::kNone),
      joined_route(routes_out ? k * k : 0, PairRoutes::kNone);
  std::vector<std::size_t> settled_by(k, 0);
  tbb::enumerable_thread_specific<std::unique_ptr<core::PathStraightener>> straighteners;
  auto straightener = [&]() -> core::PathStraightener& {
    auto& st = straighteners.local();
    if (!st) st = std::make_unique<core::PathStraightener>(graph);
    return *st;
  };
  // Source i's search done (distances d to the others): the targets it settled, straightened.
  auto straighten_direct = [&](const core::GeodesicQuery& q, std::size_t i,
                               const std::vector<core::SurfacePoint>& targets,
                               const std::vector<double>& d) {
    core::PathStraightener& st = straightener();
    core::PathRoute best;
    for (std::size_t j = 0, t = 0; j < k; ++j) {
      if (j == i) continue;
      direct[i * k + j] = d[t];
      if (std::isfinite(d[t])) {
        direct_len[i * k + j] =
            st.shortest(q, points[i], t, targets[t], d[t], routes_out ? &best : nullptr);
        if (routes_out) direct_route[i * k + j] = add_route(*routes_out, points, i, j, best);
      }
      ++t;
    }
  };

  // The pilots (none with an estimate): searched in full, their distances scale the radii.
  const std::size_t pilots = estimate ? 0 : std::min(kPilots, k);
  std::vector<double> ratios(pilots, 1.0);
  tbb::parallel_for(std::size_t{0}, pilots, [&](std::size_t p) {
    core::GeodesicQuery q(graph);
    q.set_anchored(true);
    const auto targets = others(points, p);
    std::vector<double> d;
    q.distances(points[p], targets, d);
    settled_by[p] = q.settled();
    straighten_direct(q, p, targets, d);
    ratios[p] = pilot_ratio(points, p, d);
    if (searched) searched();
  });
  const double ratio = ratios.empty() ? 1.0 : *std::max_element(ratios.begin(), ratios.end());
  const double w = graph.max_segment();
  const std::vector<double> radius = search_radii(points, estimate, pilots, ratio, w);

  // The other sources in a pipeline as in pairwise_in_arena: search (straightening what it
  // settles), the in-order barrier, then the joins with every earlier source's half.
  std::vector<Half> halves(k);
  std::vector<std::unique_ptr<core::GeodesicQuery>> owned;
  tbb::concurrent_queue<core::GeodesicQuery*> pool;
  std::mutex m;
  struct Item {
    std::size_t at = 0;  // in `order`
    core::GeodesicQuery* query = nullptr;
  };
  // note: by radius, smallest first: a search started after another then mostly ends after
  // it, so rarely waits at the barrier holding its query; and each pair joins over the shell
  // of the smaller search.
  std::vector<std::size_t> order;
  for (std::size_t i = pilots; i < k; ++i) order.push_back(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return radius[a] < radius[b]; });
  std::size_t next = 0;
  // The route through shell node t of a's half and the later search q (from i), into route.
  auto meeting_route = [&](const Half& h, std::size_t t, const core::GeodesicQuery& q,
                           std::vector<std::uint32_t>& nodes,
                           std::vector<std::array<double, 2>>& route) {
    route.clear();
    h.path_bends(t, nodes);
    for (std::uint32_t b : nodes) route.push_back({graph.position(b)[0], graph.position(b)[1]});
    q.path_to_node(h.shell[t].node, nodes);
    for (std::size_t n = nodes.size(); n-- > 0;) {
      route.push_back({graph.position(nodes[n])[0], graph.position(nodes[n])[1]});
    }
  };
  // Per join scratch.
  struct JoinScratch {
    std::vector<double> sums;
    std::vector<std::size_t> near, picked;
    std::vector<std::uint32_t> nodes;
    std::vector<std::array<double, 2>> route;
    core::PathRoute bends, best_bends;
  };
  auto join = [&](std::size_t a, std::size_t i, const core::GeodesicQuery& q, JoinScratch& js) {
    auto& [sums, near, picked, nodes, route, bends, best_bends] = js;
    const Half& h = halves[a];
    sums.resize(h.shell.size());
    double best = inf;
    std::size_t at = 0;
    for (std::size_t t = 0; t < h.shell.size(); ++t) {
      const double db = q.settled_distance(h.shell[t].node);
      sums[t] = db < inf ? h.shell[t].d + db : inf;
      if (sums[t] < best) {
        best = sums[t];
        at = t;
      }
    }
    if (!(best <= radius[a] + radius[i] - w)) return;  // not proven: measured one way
    // More meeting nodes, each the best at least one longest segment away from those taken,
    // while nearly as short: one per route around the hills between, where the graph's error
    // may have ranked the longer first.
    near.clear();
    for (std::size_t t = 0; t < h.shell.size(); ++t) {
      if (sums[t] < best * (1 + kNearTie)) near.push_back(t);
    }
    picked.assign(1, at);
    while (picked.size() < kMeetingRoutes) {
      double next_sum = inf;
      std::size_t next_at = h.shell.size();
      for (std::size_t t : near) {
        if (!(sums[t] < next_sum)) continue;
        const double* p = graph.position(h.shell[t].node);
        bool apart = true;
        for (std::size_t u : picked) {
          const double* o = graph.position(h.shell[u].node);
          if ((p[0] - o[0]) * (p[0] - o[0]) + (p[1] - o[1]) * (p[1] - o[1]) <= w * w) apart = false;
        }
        if (apart) {
          next_sum = sums[t];
          next_at = t;
        }
      }
      if (next_at == h.shell.size()) break;
      picked.push_back(next_at);
    }
    core::PathStraightener& st = straightener();
    double len_best = inf;
    for (const std::size_t t : picked) {
      meeting_route(h, t, q, nodes, route);
      const double len = st.along(points[a], route, points[i], routes_out ? &bends : nullptr);
      if (len >= 0 && len < len_best) {
        len_best = len;
        if (routes_out) std::swap(best_bends, bends);
      }
    }
    // note: the met path is a real one (up to the anchors' float rounding); pulled taut along
    // its route it is never longer. Where it is, the route left the path's faces (its part
    // told by bends cut across a hole or the outline): the pair is measured one way.
    if (!(len_best <= best * (1 + 1e-6))) return;
    const std::size_t ab = std::min(a, i) * k + std::max(a, i);
    joined_len[ab] = len_best;
    if (routes_out && len_best < inf)
      joined_route[ab] = add_route(*routes_out, points, a, i, best_bends);
  };
  // Source order[at]: searched, what it settled straightened, its half kept.
  auto search = [&](std::size_t at) {
    const std::size_t i = order[at];
    core::GeodesicQuery* q = nullptr;
    if (!pool.try_pop(q)) {
      auto made = std::make_unique<core::GeodesicQuery>(graph);
      made->set_anchored(true);
      // note: waypoints two longest segments apart: the route of a met pair's
      // earlier half strays from its path by less than a face between them (at
      // one segment apart, 1.4 x the memory for the same figures within 0.1 %).
      made->set_track_bends(true, 2 * w);
      q = made.get();
      std::lock_guard<std::mutex> lock(m);
      owned.push_back(std::move(made));
    }
    const auto targets = others(points, i);
    std::vector<double> d;
    Shell shell;
    q->explore(points[i], targets, radius[i], radius[i] - w, shell, d);
    settled_by[i] = q->settled();
    straighten_direct(*q, i, targets, d);
    // note: a later search settles nothing farther (in 3D) than its radius and one
    // bucket: the shell's nodes beyond every later one's are never joined, nor
    // those of a later one this search settled (their pair is straightened here).
    auto reached = [&](std::uint32_t v) {
      const double* p = graph.position(v);
      for (std::size_t later = at + 1; later < order.size(); ++later) {
        if (direct[i * k + order[later]] < inf) continue;
        const core::SurfacePoint& o = points[order[later]];
        const double dx = p[0] - o.x, dy = p[1] - o.y, dz = p[2] - o.z;
        const double r = radius[order[later]] + w;
        if (dx * dx + dy * dy + dz * dz <= r * r) return true;
      }
      return false;
    };
    halves[i] = Half(*q, graph.node_count(), shell, reached);
    if (searched) searched();
    return Item{at, q};
  };
  // Its joins with every earlier source's half, then its query back to the pool.
  auto joins = [&](Item item) {
    const std::size_t i = order[item.at];
    JoinScratch js;
    for (std::size_t before = 0; before < item.at; ++before) {
      const std::size_t a = order[before];
      // note: a pair either search settled is straightened from there.
      if (direct[a * k + i] < inf || direct[i * k + a] < inf) continue;
      join(a, i, *item.query, js);
    }
    pool.push(item.query);
  };
  tbb::parallel_pipeline(
      tokens, tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                                  [&](tbb::flow_control& fc) -> std::size_t {
                                                    if (next >= order.size()) fc.stop();
                                                    return next++;
                                                  }) &
                  tbb::make_filter<std::size_t, Item>(tbb::filter_mode::parallel, search) &
                  tbb::make_filter<Item, Item>(tbb::filter_mode::serial_in_order,
                                               [](Item item) { return item; }) &
                  tbb::make_filter<Item, void>(tbb::filter_mode::parallel, joins));
  owned.clear();
  halves.clear();

  // Each pair's shortest candidate; those with none are left to one-way queries.
  std::vector<char> left(k * k, 0);
  std::size_t left_count = 0;
  for (std::size_t a = 0; a < k; ++a) {
    for (std::size_t b = a + 1; b < k; ++b) {
      const std::size_t ab = a * k + b, ba = b * k + a;
      double v = inf;
      PairRoutes::Id r = PairRoutes::kNone;
      auto take = [&](double len, PairRoutes::Id route) {
        if (len < v) {
          v = len;
          r = route;
        }
      };
      take(direct_len[ab], routes_out ? direct_route[ab] : PairRoutes::kNone);
      take(direct_len[ba], routes_out ? direct_route[ba] : PairRoutes::kNone);
      take(joined_len[ab], routes_out ? joined_route[ab] : PairRoutes::kNone);
      if (v < inf) {
        out[ab] = v;
        if (routes_out) routes_out->assign(a, b, r);
      } else {
        left[ab] = 1;
        ++left_count;
      }
    }
  }
  for (std::size_t n : settled_by) stats.settled += static_cast<double>(n);
  for (const auto& st : straighteners) {
    if (!st) continue;
    stats.straightened += st->stats().paths;
    stats.straighten_passes += st->stats().passes;
    stats.reroutes += st->stats().reroutes;
    stats.straighten_failed += st->stats().failed;
  }
  if (left_count > 0) {
    // note: it gives the pairs left their routes in routes_out.
    std::vector<double> one_way(k * k, 0.0);
    measure_one_way(graph, points, left, true, one_way, stats, nullptr, routes_out);
    for (std::size_t ab = 0; ab < k * k; ++ab) {
      if (left[ab]) out[ab] = one_way[ab];
    }
  }
  stats.one_way_pairs += left_count;
  return out;
}

// pairwise_distances in the current arena, meeting searches with at most `tokens` queries at
// once; searched (if given) is called as each source's search is done.
std::vector<double> pairwise_in_arena(const core::SteinerGraph& graph,
                                      const std::vector<core::SurfacePoint>& points,
                                      const PairwiseOptions& options, PairwiseStats& stats,
                                      std::size_t tokens, const std::function<void()>& searched) {
  const PairwiseMethod method = options.method;
  const std::size_t k = points.size();
  const std::vector<double>* estimate = usable_estimate(options.estimate, k);
  std::vector<double> out(k * k, 0.0);
  std::vector<char> need(k * k, 0);
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = i + 1; j < k; ++j) need[i * k + j] = 1;
  }
  if (options.straighten && options.routes_out) {
    reset_routes(*options.routes_out, points);
  }
  if (options.straighten && method == PairwiseMethod::kMeet && k >= 3) {
    return meet_straightened(graph, points, estimate, options.routes_out, stats, tokens, searched);
  }
  if (options.straighten || method == PairwiseMethod::kOneWay || k < 3) {
    measure_one_way(graph, points, need, options.straighten, out, stats, searched,
                    options.routes_out);
    stats.one_way_pairs += k * (k - 1) / 2;
    return out;
  }
  const double inf = std::numeric_limits<double>::infinity();
  // direct[i * k + j]: GD(i, j) as settled by the search from i (infinity if it was not).
  std::vector<double> direct(k * k, inf);
  std::vector<std::size_t> settled_by(k, 0);
  const std::size_t pilots = estimate ? 0 : std::min(kPilots, k);
  const double ratio = search_pilots(graph, points, pilots, direct, settled_by, searched);
  // note: a pair joins where the searches overlap by the longest segment at least (the last
  // node of a shortest path inside one search is then settled by the other too).
  const double w = graph.max_segment();
  const std::vector<double> radius = search_radii(points, estimate, pilots, ratio, w);

  // The other sources are searched to their radii in a oneTBB pipeline of at most `tokens`
  // sources in flight, each holding one query: a serial stage hands out the sources in order,
  // their searches run in parallel, and once every source before i has passed the in-order
  // barrier (so has its shell: its settled nodes within w of its radius), i's query joins each
  // pair a < i over a's shell with i's settled distances, in parallel, and goes back to the pool.
  std::vector<Shell> shells(k);
  std::vector<double> meet(k * k, inf);
  std::vector<std::unique_ptr<core::GeodesicQuery>> owned;  // every query made (under m)
  tbb::concurrent_queue<core::GeodesicQuery*> pool;         // the ones free
  std::mutex m;
  struct Item {
    std::size_t i = 0;
    core::GeodesicQuery* query = nullptr;
  };
  std::size_t next = pilots;
  tbb::parallel_pipeline(
      tokens, tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                                  [&](tbb::flow_control& fc) -> std::size_t {
                                                    if (next >= k) fc.stop();
                                                    return next++;
                                                  }) &
                  tbb::make_filter<std::size_t, Item>(
                      tbb::filter_mode::parallel,
                      [&](std::size_t i) {
                        core::GeodesicQuery* q = nullptr;
                        if (!pool.try_pop(q)) {
                          auto made = std::make_unique<core::GeodesicQuery>(graph);
                          q = made.get();
                          std::lock_guard<std::mutex> lock(m);
                          owned.push_back(std::move(made));
                        }
                        std::vector<double> d;
                        q->explore(points[i], others(points, i), radius[i], radius[i] - w,
                                   shells[i], d);
                        settled_by[i] = q->settled();
                        for (std::size_t j = 0, t = 0; j < k; ++j) {
                          if (j != i) direct[i * k + j] = d[t++];
                        }
                        if (searched) searched();
                        return Item{i, q};
                      }) &
                  tbb::make_filter<Item, Item>(tbb::filter_mode::serial_in_order,
                                               [](Item item) { return item; }) &
                  tbb::make_filter<Item, void>(tbb::filter_mode::parallel, [&](Item item) {
                    for (std::size_t a = pilots; a < item.i; ++a) {
                      double best = inf;
                      for (const auto& [v, da] : shells[a]) {
                        const double db = item.query->settled_distance(v);
                        if (db < inf) best = std::min(best, da + db);
                      }
                      meet[a * k + item.i] = best;
                    }
                    pool.push(item.query);
                  }));
  std::vector<char> left(k * k, 0);
  const std::size_t left_count = settle_pairs(direct, meet, radius, w, pilots, k, out, left);
  for (std::size_t n : settled_by) stats.settled += static_cast<double>(n);
  owned.clear();  // the one-way queries below take their memory
  if (left_count > 0) measure_one_way(graph, points, left, false, out, stats, nullptr);
  stats.one_way_pairs += left_count;
  return out;
}

}  // namespace

double pair_array_bytes(double k, double sets, bool straightened) {
  const double per_set = straightened ? 6 : 2, per_stage = straightened ? 10 : 4;
  return (per_set * sets + per_stage) * k * k * static_cast<double>(sizeof(double));
}

std::vector<double> pairwise_distances(const core::SteinerGraph& graph,
                                       const std::vector<core::SurfacePoint>& points,
                                       const PairwiseOptions& options, PairwiseStats* stats) {
  const PairwiseMethod method = options.method;
  const std::size_t max_searches = options.max_searches;
  const std::size_t threads = worker_threads();
  std::size_t workers = threads, tokens = unbounded_searches(threads, options.straighten);
  if (max_searches > 0) {
    if (max_searches < min_searches(method)) {
      throw std::invalid_argument("pairwise_distances: fewer searches than it needs at once");
    }
    // note: one way, each worker holds one query: as many workers as searches. Meeting, each
    // source in the pipeline holds one (the one-way leftovers run after those are freed).
    if (method == PairwiseMethod::kMeet) {
      tokens = max_searches;
    } else {
      workers = std::min(threads, max_searches);
    }
  }
  std::mutex report_mutex;
  std::size_t searched_count = 0;
  std::function<void()> searched;
  if (options.on_search) {
    searched = [&] {
      std::lock_guard<std::mutex> lock(report_mutex);
      options.on_search(++searched_count);
    };
  }
  PairwiseStats local;
  PairwiseStats& st = stats ? *stats : local;
  if (workers == threads) return pairwise_in_arena(graph, points, options, st, tokens, searched);
  tbb::task_arena arena(static_cast<int>(workers));
  return arena.execute(
      [&] { return pairwise_in_arena(graph, points, options, st, tokens, searched); });
}

std::size_t shorten_along(const core::SteinerGraph& graph,
                          const std::vector<core::SurfacePoint>& points, const PairRoutes& routes,
                          std::vector<double>& distances, PairRoutes* shortened_routes) {
  const std::size_t k = points.size();
  std::vector<std::size_t> shortened(k, 0);
  tbb::enumerable_thread_specific<std::unique_ptr<core::PathStraightener>> scratch;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, k, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      auto& st = scratch.local();
                      if (!st) st = std::make_unique<core::PathStraightener>(graph);
                      std::vector<std::array<double, 2>> bends, taut;
                      core::PathRoute along_route, follow_route;
                      core::PathRoute* const along_out = shortened_routes ? &along_route : nullptr;
                      core::PathRoute* const follow_out =
                          shortened_routes ? &follow_route : nullptr;
                      for (std::size_t a = r.begin(); a < r.end(); ++a) {
                        for (std::size_t b = a + 1; b < k; ++b) {
                          double& d = distances[a * k + b];
                          if (!std::isfinite(d) || !routes.get(a, b, bends, taut)) continue;
                          // note: both ways, each finding paths the other does not: its bends
                          // snapped to graph nodes (a shorter path nearby, the meshes' faces
                          // differing), and the taut path's own faces (on cliffs, where the
                          // nodes are sparse, the same path: a synthetic volcano's 10 % mesh
                          // measured 24 % high without, 0.1 % with).
                          double len = st->along(points[a], bends, points[b], along_out);
                          const double followed =
                              st->follow(points[a], taut, points[b], follow_out);
                          const bool by_follow = followed >= 0 && (len < 0 || followed < len);
                          if (by_follow) len = followed;
                          // note: only a shorter route, not the same one rounded otherwise (a mesh
                          // measured against itself gives 0).
                          if (len >= 0 && len < d * (1 - 1e-12)) {
                            d = len;
                            ++shortened[a];
                            if (shortened_routes) {
                              shortened_routes->assign(
                                  a, b,
                                  add_route(*shortened_routes, points, a, b,
                                            by_follow ? follow_route : along_route));
                            }
                          }
                        }
                      }
                    });
  std::size_t total = 0;
  for (std::size_t n : shortened) total += n;
  return total;
}

namespace {

// The geodesics of both meshes: exact (CGAL), or on their Steiner graphs (one at a time).
struct Geodesics {
  std::unique_ptr<core::ExactGeodesics> exact_t, exact_s;
  std::unique_ptr<core::SteinerGraph> graph_t, graph_s;
};

// Builds the exact geodesics of both meshes, then says so through stage.
Geodesics build_exact(const core::TriMesh& original, const core::TriMesh& simplified,
                      const std::function<void(const std::string&)>& stage) {
  Geodesics g;
  try {
    g.exact_t = std::make_unique<core::ExactGeodesics>(original);
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string("the DEM's grid TIN: ") + e.what());
  }
  g.exact_s = std::make_unique<core::ExactGeodesics>(simplified);
  stage("exact geodesics (CGAL): T " + std::to_string(original.faces.size()) + " faces, T' " +
        std::to_string(simplified.faces.size()) + " faces");
  return g;
}

// The Steiner graphs' spacings, their memory and the searches the budget holds, into result.
// note: the graphs are built one after the other, each freed before the next: the peak holds
// the larger one and its searches.
// The pairs' arrays count in the budget too (pairs_bytes), and straightened, each set's routes on
// both meshes (PairRoutes), kept for the other mesh, are held in memory up to half the budget's
// slack, at most kRoutesMemory in all (routes_bytes; the rest in a temporary file).
void plan_graphs(const core::TriMesh& original, const core::TriMesh& simplified,
                 const EvalOptions& options, PairwiseMethod& method, std::size_t k_max,
                 std::size_t sets, EvalResult& result) {
  // note: the paper's Steiner distances need one delta on both meshes (their bias depends on
  // it); straightened ones are exact but for near ties, whose share depends on the spacing
  // relative to the mesh's own faces, so each mesh gets its own.
  if (options.delta_m > 0) {
    result.delta_m = result.delta_mesh_m = options.delta_m;
  } else if (options.straighten) {
    // note: never finer on T' than on T, so that T measured against itself gives 0.
    result.delta_m = kStraightenedDeltaFactorDem * core::mean_edge_length(original);
    result.delta_mesh_m =
        std::max(kStraightenedDeltaFactor * core::mean_edge_length(simplified), result.delta_m);
  } else {
    result.delta_m = result.delta_mesh_m = kDefaultDeltaFactor * core::mean_edge_length(original);
  }
  const auto est_t = core::SteinerGraph::estimate(original, result.delta_m);
  const auto est_s = core::SteinerGraph::estimate(simplified, result.delta_mesh_m);
  result.graphs_bytes = std::max(est_t.bytes, est_s.bytes);
  result.search_bytes = core::GeodesicQuery::estimate_bytes(
      std::max(est_t.nodes, est_s.nodes), std::max(original.faces.size(), simplified.faces.size()),
      k_max, options.straighten);
  const bool routes = options.straighten;
  result.pairs_bytes = static_cast<std::size_t>(
      pair_array_bytes(static_cast<double>(k_max), static_cast<double>(sets), routes));
  result.routes_bytes = routes ? kRoutesMemory : 0;
  if (options.memory_budget_bytes > 0) {
    // note: straightened pairs can be measured one way, one search at a time: slower (each
    // search about twice the graph) but within a budget that two searches do not fit.
    auto need_for = [&](PairwiseMethod m) {
      return result.graphs_bytes + min_searches(m) * result.search_bytes + result.pairs_bytes;
    };
    if (options.straighten && method == PairwiseMethod::kMeet &&
        need_for(PairwiseMethod::kMeet) > options.memory_budget_bytes &&
        need_for(PairwiseMethod::kOneWay) <= options.memory_budget_bytes) {
      method = PairwiseMethod::kOneWay;
    }
    const std::size_t need = need_for(method);
    if (need > options.memory_budget_bytes) {
      throw InputError(
          "the geodesics need about " + format_bytes(static_cast<double>(need)) +
          " (a Steiner graph of " + format_bytes(static_cast<double>(result.graphs_bytes)) + ", " +
          std::to_string(min_searches(method)) + " searches of " +
          format_bytes(static_cast<double>(result.search_bytes)) + ", the pairs' arrays " +
          format_bytes(static_cast<double>(result.pairs_bytes)) + "), more than the " +
          format_bytes(static_cast<double>(options.memory_budget_bytes)) +
          " available (--max-memory); use a larger --delta or fewer --points");
    }
    if (routes) {
      result.routes_bytes = std::min(kRoutesMemory, (options.memory_budget_bytes - need) / 2);
    }
    const std::size_t threads = worker_threads();
    result.max_searches = std::min((options.memory_budget_bytes - result.graphs_bytes -
                                    result.pairs_bytes - result.routes_bytes) /
                                       result.search_bytes,
                                   unbounded_searches(threads, options.straighten));
  }
}

// Builds the Steiner graph of T (on_t) or T' into geo, the other one freed first (with its
// vertices' angles where paths are straightened); its size into result, then says so through
// stage.
void build_graph(Geodesics& geo, bool on_t, const core::TriMesh& mesh, bool straighten,
                 EvalResult& result, const std::function<void(const std::string&)>& stage) {
  geo.graph_t.reset();
  geo.graph_s.reset();
  auto& graph = on_t ? geo.graph_t : geo.graph_s;
  graph = std::make_unique<core::SteinerGraph>(mesh, on_t ? result.delta_m : result.delta_mesh_m);
  if (straighten) graph->keep_vertex_angles();
  (on_t ? result.original_nodes : result.simplified_nodes) = graph->node_count();
  stage(std::string("Steiner graph of ") + (on_t ? "T: " : "T': ") +
        std::to_string(graph->node_count()) + " nodes");
}

// The points xy located on a mesh (snapped within snap_m, counted into snapped); an
// InputError saying how many of the set's points lie outside `footprint` if any do.
std::vector<core::SurfacePoint> locate_all(const core::PointLocator& locate,
                                           const std::vector<std::array<double, 2>>& xy,
                                           double snap_m, std::size_t& snapped,
                                           const std::string& what, const std::string& footprint) {
  std::vector<core::SurfacePoint> out;
  std::size_t outside = 0;
  for (const auto& p : xy) {
    const auto hit = locate.locate(p[0], p[1], snap_m);
    if (!hit) {
      ++outside;
      continue;
    }
    snapped += hit->snapped;
    out.push_back(hit->point);
  }
  if (outside > 0) {
    throw InputError(std::to_string(outside) + " of " + std::to_string(xy.size()) + what +
                     " lie outside " + footprint);
  }
  return out;
}

// One set's error from its pair distances on T (dt) and T' (ds), k x k, into result.
// note: never silently wrong: a pair T connects but T' does not fails the run (the mesh is in
// parts or slit); a pair T does not connect has no distance to compare and is counted apart.
void score_set(const std::vector<double>& dt, const std::vector<double>& ds, std::size_t k,
               std::size_t set, const std::string& set_name, bool keep_pairs, EvalResult& result) {
  double sum = 0.0;
  std::size_t measured = 0, unconnected = 0, coincident = 0, broken = 0;
  for (std::size_t i = 0; i < k; ++i) {
    for (std::size_t j = i + 1; j < k; ++j) {
      const double a = dt[i * k + j], b = ds[i * k + j];
      if (keep_pairs) {
        result.pairs.push_back({static_cast<std::uint32_t>(set), static_cast<std::uint32_t>(i),
                                static_cast<std::uint32_t>(j), a, b});
      }
      if (!std::isfinite(a)) {
        ++unconnected;
      } else if (!(a > 0)) {
        ++coincident;
      } else if (!std::isfinite(b)) {
        ++broken;
      } else {
        sum += std::fabs(a - b) / a;
        ++measured;
      }
    }
  }
  if (broken > 0) {
    throw InputError("the mesh does not connect " + std::to_string(broken) + " of the " +
                     std::to_string(broken + measured) + " pairs of " + set_name +
                     " that T connects (is it in several parts, or slit?)");
  }
  if (measured == 0) {
    throw InputError(set_name + ": none of its " + std::to_string(k * (k - 1) / 2) +
                     " pairs can be measured (" + std::to_string(unconnected) +
                     " not connected on T, " + std::to_string(coincident) + " at distance 0 on T)");
  }
  result.pairs_measured += measured;
  result.pairs_unconnected += unconnected;
  result.pairs_coincident += coincident;
  result.set_errors.push_back(sum / static_cast<double>(measured));
}

// The paper's Steiner distances (not straightened) of the pairs of points on graph's mesh: a
// guess at their geodesics on another surface of the same points (PairwiseOptions::estimate).
std::vector<double> guess_distances(const core::SteinerGraph& graph,
                                    const std::vector<core::SurfacePoint>& points,
                                    PairwiseMethod method, const EvalResult& result) {
  PairwiseOptions po;
  po.method = method;
  po.straighten = false;
  // note: a plain search holds a third of a straightened one's labels: the budget fits as many.
  po.max_searches = result.max_searches;
  return pairwise_distances(graph, points, po);
}

// One geodesic stage: the pairs of points on T (on_t) or T', exact or on the Steiner graph,
// its progress reported as its sources finish (stage `name`); Cancelled when it was stopped.
std::vector<double> geodesic_stage(const Geodesics& geo, bool on_t,
                                   const std::vector<core::SurfacePoint>& points,
                                   const EvalOptions& options, PairwiseMethod method,
                                   std::size_t max_searches, const std::string& name,
                                   const core::Progress& progress, PairwiseStats& stats,
                                   PairRoutes* routes_out, const std::vector<double>* estimate) {
  bool stop = false;  // note: written under the report lock of the pairwise call, read after it
  const std::size_t k = points.size();
  std::vector<double> d;
  if (options.exact) {
    std::function<bool(std::size_t)> on_source;
    if (progress) {
      // note: the exact sources take seconds each: a stop ends the stage at once
      on_source = [&](std::size_t done) {
        return progress(static_cast<double>(done) / static_cast<double>(k - 1), name);
      };
    }
    d = exact_pairwise_distances(on_t ? *geo.exact_t : *geo.exact_s, points, on_source);
  } else {
    PairwiseOptions po;
    const core::SteinerGraph& graph = on_t ? *geo.graph_t : *geo.graph_s;
    po.method = method;
    // note: straightened, the searches meet only on a mesh that is one disk (Euler
    // characteristic V - E + F = 1: one piece, no hole). Around a hole (a DEM's voids) two
    // routes of one pair are often nearly equal, and a met pair's half told by its bends may
    // cut across the hole: on pyrenees_andorra_voids some met pairs came out 1-11 % long.
    const auto& mesh = graph.mesh();
    const auto euler = static_cast<long long>(mesh.vertex_count()) -
                       static_cast<long long>(graph.edge_count()) +
                       static_cast<long long>(mesh.faces.size());
    if (options.straighten && euler != 1) po.method = PairwiseMethod::kOneWay;
    po.straighten = options.straighten;
    po.max_searches = max_searches;
    po.routes_out = routes_out;
    po.estimate = estimate;
    if (progress) {
      po.on_search = [&](std::size_t searched) {
        if (!progress(static_cast<double>(searched) / static_cast<double>(k), name)) stop = true;
      };
    }
    d = pairwise_distances(graph, points, po, &stats);
  }
  if (stop) throw Cancelled();
  return d;
}

}  // namespace

EvalResult evaluate_distances(const core::TriMesh& original, const core::TriMesh& simplified,
                              const EvalOptions& options, const core::Progress& progress) {
  auto stage = [&](const std::string& what) {
    if (progress && !progress(0.0, what)) throw Cancelled();
  };
  EvalResult result;
  result.exact = options.exact;
  // note: one way where a memory budget fits only one search (plan_graphs).
  PairwiseMethod method = options.method;
  const bool given = !options.sample_xy.empty();
  const std::size_t sets =
      given ? options.sample_xy.size() : static_cast<std::size_t>(options.sets);
  std::size_t k_max = given ? 0 : static_cast<std::size_t>(options.points);
  for (const auto& set : options.sample_xy) k_max = std::max(k_max, set.size());
  // Sets are named as their user knows them: from 1 when drawn here, by their number in the
  // file (from 0) when given.
  auto set_name = [&](std::size_t set) {
    return given ? "sample set " + std::to_string(set) : "set " + std::to_string(set + 1);
  };
  Geodesics geo;
  if (options.exact) {
    geo = build_exact(original, simplified, stage);
  } else {
    plan_graphs(original, simplified, options, method, k_max, sets, result);
  }
  const core::PointLocator locate_s(simplified);
  std::optional<core::PointLocator> locate_t;
  if (given) locate_t.emplace(original);

  // Every set's points on T (drawn, or given and located), then on T'.
  std::vector<std::vector<core::SurfacePoint>> on_t(sets), on_s(sets);
  std::vector<std::string> stage_names(sets);
  for (std::size_t set = 0; set < sets; ++set) {
    if (given) {
      on_t[set] = locate_all(*locate_t, options.sample_xy[set], options.snap_m, result.snapped,
                             " points of " + set_name(set), "the DEM's footprint");
    } else {
      const std::uint64_t seed =
          options.seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(set) + 1;
      on_t[set] = core::sample_uniform(original, static_cast<std::size_t>(options.points), seed);
    }
    std::vector<std::array<double, 2>> xy_t(on_t[set].size());
    for (std::size_t i = 0; i < xy_t.size(); ++i) xy_t[i] = {on_t[set][i].x, on_t[set][i].y};
    on_s[set] = locate_all(locate_s, xy_t, options.snap_m, result.snapped,
                           (given ? " points of " : " sample points of ") + set_name(set),
                           "the mesh's footprint");
    stage_names[set] =
        given ? set_name(set) + " (" + std::to_string(set + 1) + "/" + std::to_string(sets) + ")"
              : "set " + std::to_string(set + 1) + "/" + std::to_string(sets);
  }

  // The geodesics, one mesh at a time: T' first (its graph, small, checks the mesh before the
  // long work on T), then T, each graph freed before the next is built. Then, straightened,
  // each pair's route on either mesh is tried on the other (shorten_along): T' is built again.
  PairwiseStats stats_t, stats_s;
  std::vector<std::vector<double>> dt(sets), ds(sets);
  const bool routes = options.straighten && !options.exact;
  // Straightened: each set's pairs' paper Steiner distances on T' (one quick search a source),
  // from which the meeting radii on both meshes are scaled.
  std::vector<std::vector<double>> guess(routes ? sets : 0);
  // Each set's routes: found on T', found on T, and T's paths that T''s routes shortened.
  // note: at most 3 x sets of them hold routes at once (each set's on T' until T's stage has
  // tried them, those on T until T' has, and then each round's), each within its share of the
  // memory planned.
  std::vector<PairRoutes> routes_t, routes_s, shortened_t;
  const std::size_t share = result.routes_bytes / (3 * sets);
  if (routes) {
    for (std::size_t set = 0; set < sets; ++set) {
      routes_t.emplace_back(share);
      routes_s.emplace_back(share);
      shortened_t.emplace_back(share);
    }
  }
  const std::string kind = options.exact ? ": exact geodesics on T" : ": geodesics on T";
  for (const bool mesh_t : {false, true}) {
    if (!options.exact) {
      build_graph(geo, mesh_t, mesh_t ? original : simplified, options.straighten, result, stage);
    }
    for (std::size_t set = 0; set < sets; ++set) {
      const std::string name = stage_names[set] + kind + (mesh_t ? "" : "'");
      stage(name);
      const auto t0 = std::chrono::steady_clock::now();
      // note: one way (a memory budget that fits one search) has no radii to scale.
      if (!mesh_t && routes && method == PairwiseMethod::kMeet) {
        guess[set] = guess_distances(*geo.graph_s, on_s[set], method, result);
      }
      // note: the paper's distances on T scale from T''s; straightened, both meshes' from the
      // same guess, so that a mesh identical to T measures 0 (up to rounding).
      const std::vector<double>* estimate = routes                     ? &guess[set]
                                            : mesh_t && !options.exact ? &ds[set]
                                                                       : nullptr;
      (mesh_t ? dt : ds)[set] =
          geodesic_stage(geo, mesh_t, mesh_t ? on_t[set] : on_s[set], options, method,
                         result.max_searches, name, progress, mesh_t ? stats_t : stats_s,
                         routes ? &(mesh_t ? routes_t : routes_s)[set] : nullptr, estimate);
      if (mesh_t && routes) {
        // note: a pair shortened gets its new route too, for T' to try beside T's own (which
        // may still be the shorter there).
        reset_routes(shortened_t[set], on_t[set]);
        result.shortened +=
            shorten_along(*geo.graph_t, on_t[set], routes_s[set], dt[set], &shortened_t[set]);
        routes_s[set] = PairRoutes();
      }
      const double secs =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      (mesh_t ? result.original_s : result.simplified_s) += secs;
    }
  }
  if (routes) {
    // Each set's routes of T tried on T' (built again), then, rounds by turns, the paths each
    // mesh's last round shortened tried on the other, while any round shortens some and at
    // most kRouteRounds rounds.
    // note: T's search and straightening may end on a locally shortest path round the wrong
    // side of a saddle vertex (total angle above 2 pi), and so may T''s, on other pairs; the
    // other mesh's route, pulled taut, mostly passes it on the right side. On a pyramid's 10 %
    // mesh, which keeps T's surface, a pair stayed 6e-4 long on T (its route on T' exact) and
    // another on T': the measure 3.7e-6 where exact geodesics give 4e-12.
    std::vector<PairRoutes> tried = std::move(shortened_t), shortened;
    bool on_t_now = false;
    for (int round = 0; round < kRouteRounds; ++round) {
      auto t0 = std::chrono::steady_clock::now();
      build_graph(geo, on_t_now, on_t_now ? original : simplified, true, result, stage);
      std::size_t n = 0;
      shortened.clear();
      for (std::size_t set = 0; set < sets; ++set) {
        stage(stage_names[set] + (on_t_now ? ": routes of T' on T" : ": routes of T on T'") +
              (round > 1 ? " again" : ""));
        shortened.emplace_back(share);
        const auto& points = on_t_now ? on_t[set] : on_s[set];
        // note: the last round's shortened paths have no round after them to try them.
        PairRoutes* const out = round + 1 < kRouteRounds ? &shortened.back() : nullptr;
        if (out) reset_routes(*out, points);
        const auto& graph = on_t_now ? *geo.graph_t : *geo.graph_s;
        auto& d = (on_t_now ? dt : ds)[set];
        if (round == 0) {
          n += shorten_along(graph, points, routes_t[set], d, out);
          routes_t[set] = PairRoutes();
        }
        n += shorten_along(graph, points, tried[set], d, out);
        tried[set] = PairRoutes();
      }
      result.shortened += n;
      (on_t_now ? result.original_s : result.simplified_s) +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (n == 0) break;
      tried.swap(shortened);
      on_t_now = !on_t_now;
    }
  }
  geo = Geodesics();
  double queries = 0;  // Steiner queries: one per source
  for (std::size_t set = 0; set < sets; ++set) {
    queries += static_cast<double>(on_t[set].size());
    score_set(dt[set], ds[set], on_t[set].size(), set, set_name(set), options.keep_pairs, result);
  }
  result.original_one_way = stats_t.one_way_pairs;
  result.simplified_one_way = stats_s.one_way_pairs;
  result.straightened = stats_t.straightened + stats_s.straightened;
  result.straighten_failed = stats_t.straighten_failed + stats_s.straighten_failed;
  result.straighten_passes = stats_t.straighten_passes + stats_s.straighten_passes;
  result.reroutes = stats_t.reroutes + stats_s.reroutes;
  // note: k queries per set, one per source (a source with no pair to measure settles none).
  if (!options.exact && queries > 0) {
    result.original_searched = stats_t.settled / (queries * result.original_nodes);
    result.simplified_searched = stats_s.settled / (queries * result.simplified_nodes);
  }
  double total = 0.0;
  for (double e : result.set_errors) total += e;
  result.distance_error = result.set_errors.empty() ? 0.0 : total / result.set_errors.size();
  return result;
}

}  // namespace dpts::par

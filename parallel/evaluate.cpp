// Parallel geodesic queries and the distance-preserving error.
#include "parallel/evaluate.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <string>

#include "core/errors.hpp"
#include "core/surface_sampling.hpp"

namespace dpts::par {

std::vector<double> pairwise_distances(const core::SteinerGraph& graph,
                                       const std::vector<core::SurfacePoint>& points,
                                       double* settled) {
  const std::size_t k = points.size();
  std::vector<double> out(k * k, 0.0);
  // Each pair is measured once, by a Dijkstra from the endpoint that ranks the other nearer
  // (straight-line distance): every query then stops at about its nearest half of the points
  // instead of the farthest, which roughly halves the area searched.
  auto d2 = [&](std::size_t i, std::size_t j) {
    const double dx = points[i].x - points[j].x, dy = points[i].y - points[j].y,
                 dz = points[i].z - points[j].z;
    return dx * dx + dy * dy + dz * dz;
  };
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
      if (rank[i][j] <= rank[j][i]) {
        assigned[i].push_back(j);
      } else {
        assigned[j].push_back(i);
      }
    }
  }
  std::vector<std::size_t> settled_by(k, 0);  // per source: the same sum for any thread count
  tbb::enumerable_thread_specific<std::unique_ptr<core::GeodesicQuery>> queries;
  // note: grain 1: query costs differ a lot; let the scheduler balance them.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, k, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      auto& q = queries.local();
                      if (!q) q = std::make_unique<core::GeodesicQuery>(graph);
                      std::vector<core::SurfacePoint> targets;
                      std::vector<double> d;
                      for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        if (assigned[i].empty()) continue;
                        targets.clear();
                        for (std::size_t j : assigned[i]) targets.push_back(points[j]);
                        q->distances(points[i], targets, d);
                        settled_by[i] = q->settled();
                        for (std::size_t t = 0; t < assigned[i].size(); ++t) {
                          const std::size_t j = assigned[i][t];
                          out[std::min(i, j) * k + std::max(i, j)] = d[t];
                        }
                      }
                    });
  if (settled) {
    for (std::size_t n : settled_by) *settled += static_cast<double>(n);
  }
  return out;
}

EvalResult evaluate_distances(const core::TriMesh& original, const core::TriMesh& simplified,
                              const EvalOptions& options, const StageProgress& progress) {
  auto stage = [&](const std::string& what) {
    if (progress && !progress(what)) throw Cancelled();
  };
  EvalResult result;
  result.delta_m = options.delta_m > 0 ? options.delta_m
                                       : kDefaultDeltaFactor * core::mean_edge_length(original);
  const core::SteinerGraph graph_t(original, result.delta_m);
  const core::SteinerGraph graph_s(simplified, result.delta_m);
  result.original_nodes = graph_t.node_count();
  result.simplified_nodes = graph_s.node_count();
  stage("Steiner graphs: T " + std::to_string(result.original_nodes) + " nodes, T' " +
        std::to_string(result.simplified_nodes) + " nodes");
  const core::PointLocator locate_s(simplified);
  const auto k = static_cast<std::size_t>(options.points);
  double settled_t = 0, settled_s = 0;
  for (int set = 0; set < options.sets; ++set) {
    const std::uint64_t seed =
        options.seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(set) + 1;
    const std::vector<core::SurfacePoint> on_t = core::sample_uniform(original, k, seed);
    std::vector<core::SurfacePoint> on_s;
    std::size_t outside = 0;
    for (const auto& p : on_t) {
      const auto hit = locate_s.locate(p.x, p.y, options.snap_m);
      if (!hit) {
        ++outside;
        continue;
      }
      result.snapped += hit->snapped;
      on_s.push_back(hit->point);
    }
    if (outside > 0) {
      throw InputError(std::to_string(outside) + " of " + std::to_string(k) +
                       " sample points of set " + std::to_string(set + 1) +
                       " lie outside the mesh's footprint");
    }
    const std::string set_name =
        "set " + std::to_string(set + 1) + "/" + std::to_string(options.sets);
    stage(set_name + ": geodesics on T");
    auto t0 = std::chrono::steady_clock::now();
    const std::vector<double> dt = pairwise_distances(graph_t, on_t, &settled_t);
    auto t1 = std::chrono::steady_clock::now();
    stage(set_name + ": geodesics on T'");
    const std::vector<double> ds = pairwise_distances(graph_s, on_s, &settled_s);
    auto t2 = std::chrono::steady_clock::now();
    result.original_s += std::chrono::duration<double>(t1 - t0).count();
    result.simplified_s += std::chrono::duration<double>(t2 - t1).count();
    double sum = 0.0;
    std::size_t pairs = 0;
    for (std::size_t i = 0; i < k; ++i) {
      for (std::size_t j = i + 1; j < k; ++j) {
        const double a = dt[i * k + j], b = ds[i * k + j];
        if (a > 0 && std::isfinite(a) && std::isfinite(b)) {
          sum += std::fabs(a - b) / a;
          ++pairs;
        }
      }
    }
    result.set_errors.push_back(pairs ? sum / pairs : 0.0);
  }
  // note: k queries per set, one per source (a source with no pair to measure settles none).
  const double queries = static_cast<double>(k) * options.sets;
  if (queries > 0) {
    result.original_searched = settled_t / (queries * result.original_nodes);
    result.simplified_searched = settled_s / (queries * result.simplified_nodes);
  }
  double total = 0.0;
  for (double e : result.set_errors) total += e;
  result.distance_error = result.set_errors.empty() ? 0.0 : total / result.set_errors.size();
  return result;
}

}  // namespace dpts::par

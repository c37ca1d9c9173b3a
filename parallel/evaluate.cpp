// Parallel geodesic queries and the distance-preserving error.
#include "parallel/evaluate.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <memory>
#include <string>

#include "core/errors.hpp"
#include "core/surface_sampling.hpp"

namespace dpts::par {

std::vector<double> pairwise_distances(const core::SteinerGraph& graph,
                                       const std::vector<core::SurfacePoint>& points) {
  const std::size_t k = points.size();
  std::vector<double> out(k * k, 0.0);
  tbb::enumerable_thread_specific<std::unique_ptr<core::GeodesicQuery>> queries;
  // note: grain 1: the first sources have the most targets; let the scheduler balance them.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, k > 0 ? k - 1 : 0, 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      auto& q = queries.local();
                      if (!q) q = std::make_unique<core::GeodesicQuery>(graph);
                      std::vector<core::SurfacePoint> targets;
                      std::vector<double> d;
                      for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        targets.assign(points.begin() + static_cast<std::ptrdiff_t>(i) + 1, points.end());
                        q->distances(points[i], targets, d);
                        for (std::size_t j = i + 1; j < k; ++j) out[i * k + j] = d[j - i - 1];
                      }
                    });
  return out;
}

EvalResult evaluate_distances(const core::TriMesh& original, const core::TriMesh& simplified,
                              const EvalOptions& options) {
  EvalResult result;
  result.delta_m = options.delta_m > 0 ? options.delta_m
                                       : kDefaultDeltaFactor * core::mean_edge_length(original);
  const core::SteinerGraph graph_t(original, result.delta_m);
  const core::SteinerGraph graph_s(simplified, result.delta_m);
  result.original_nodes = graph_t.node_count();
  result.simplified_nodes = graph_s.node_count();
  const core::PointLocator locate_s(simplified);
  const auto k = static_cast<std::size_t>(options.points);
  for (int set = 0; set < options.sets; ++set) {
    const std::uint64_t seed = options.seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(set) + 1;
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
      throw InputError(std::to_string(outside) + " of " + std::to_string(k) + " sample points of set " +
                       std::to_string(set + 1) + " lie outside the mesh's footprint");
    }
    const std::vector<double> dt = pairwise_distances(graph_t, on_t);
    const std::vector<double> ds = pairwise_distances(graph_s, on_s);
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
  double total = 0.0;
  for (double e : result.set_errors) total += e;
  result.distance_error = result.set_errors.empty() ? 0.0 : total / result.set_errors.size();
  return result;
}

}  // namespace dpts::par

// All-pairs exact geodesics: one CGAL propagation per source, in parallel.
#include "parallel/exact_pairwise.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <mutex>

#include "core/errors.hpp"

namespace dpts::par {

std::vector<double> exact_pairwise_distances(const core::ExactGeodesics& geodesics,
                                             const std::vector<core::SurfacePoint>& points,
                                             const std::function<bool(std::size_t)>& on_source) {
  const std::size_t k = points.size();
  std::vector<double> out(k * k, 0.0);
  if (k < 2) return out;
  std::mutex report_mutex;
  std::size_t done = 0;
  std::atomic<bool> stop{false};
  // note: grain 1: a source costs seconds (a full propagation whatever its targets), so every
  // source is its own task; each writes only its own row of out.
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, k - 1, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          if (stop.load(std::memory_order_relaxed)) return;
          const std::vector<core::SurfacePoint> targets(points.begin() + i + 1, points.end());
          const std::vector<double> d = geodesics.distances(points[i], targets);
          for (std::size_t t = 0; t < d.size(); ++t) out[i * k + i + 1 + t] = d[t];
          if (on_source) {
            std::lock_guard<std::mutex> lock(report_mutex);
            if (!on_source(++done)) stop.store(true, std::memory_order_relaxed);
          }
        }
      });
  if (stop.load()) throw Cancelled();
  return out;
}

}  // namespace dpts::par

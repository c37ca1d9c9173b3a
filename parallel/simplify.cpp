// Whole-DEM simplification: CGAL triangulation, parallel initial importance, elimination.
#include "parallel/simplify.hpp"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <utility>

#include "core/errors.hpp"

namespace dpts::par {
namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

namespace {
constexpr std::pair<Algorithm, const char*> kAlgorithmNames[] = {
    {Algorithm::vp, "vp"},           {Algorithm::pld, "pld"},
    {Algorithm::vp_meta, "vp-meta"}, {Algorithm::pld_meta, "pld-meta"},
    {Algorithm::qslim, "qslim"},     {Algorithm::qem, "qem"}};
}  // namespace

const char* name_of(Algorithm a) {
  for (const auto& [algo, name] : kAlgorithmNames) {
    if (algo == a) return name;
  }
  return "?";
}

std::optional<Algorithm> parse_algorithm(std::string_view name) {
  for (const auto& [algo, n] : kAlgorithmNames) {
    if (name == n) return algo;
  }
  return std::nullopt;
}

int thread_count(int requested) {
  return requested > 0 ? requested : tbb::info::default_concurrency();
}

std::size_t target_count(const KeepTarget& target, std::size_t input) {
  std::size_t n = input;
  if (target.vertices) {
    n = *target.vertices;
  } else if (target.percent) {
    n = static_cast<std::size_t>(
        std::llround(*target.percent / 100.0 * static_cast<double>(input)));
  }
  return std::min(input, std::max<std::size_t>(3, n));
}

core::Tin simplify_dem(const core::HeightGrid& grid, const core::GridFrame& frame,
                       const core::EliminationOptions& options, const KeepTarget& target,
                       const core::Progress& progress, SimplifyStats* stats) {
  SimplifyStats local;
  SimplifyStats& st = stats ? *stats : local;
  auto t0 = std::chrono::steady_clock::now();
  if (progress && !progress(0.0, "triangulate")) throw Cancelled();
  core::Eliminator elim(grid, frame, options, progress);
  st.input_vertices = elim.vertex_count();
  st.target_vertices = target_count(target, st.input_vertices);
  st.triangulate_s = seconds_since(t0);

  // The initial importance of every vertex depends only on the triangulation: compute it in
  // parallel, each task writing its own vertices' slots.
  t0 = std::chrono::steady_clock::now();
  if (progress && !progress(0.0, "importance")) throw Cancelled();
  {
    // Progress after each block, serialized; a refusal skips the blocks left.
    std::mutex lock;
    std::size_t done = 0;
    std::atomic<bool> stop{false};
    const double n = static_cast<double>(elim.vertex_count());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, elim.vertex_count(), 2048),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        if (stop) return;
                        elim.compute_importance(r.begin(), r.end());
                        std::lock_guard<std::mutex> hold(lock);
                        done += r.size();
                        if (progress && !progress(static_cast<double>(done) / n, "importance")) {
                          stop = true;
                        }
                      });
    if (stop) throw Cancelled();
  }
  st.importance_s = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  elim.eliminate(st.target_vertices, progress);
  core::Tin tin = elim.tin();
  st.kept_vertices = tin.cells.size();
  st.simplify_s = seconds_since(t0);
  return tin;
}

}  // namespace dpts::par

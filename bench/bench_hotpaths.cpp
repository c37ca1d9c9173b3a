// Microbenchmarks of the hot paths, single-threaded, with throughput counters:
//   BM_importance/vp, /pld   initial importance of every vertex (simulated removal + VP or PLD)
//                            of the 153k-cell St Helens DEM: vertices/s
//   BM_remove_with_update    Delaunay removal of the least important vertex and re-evaluation of
//                            its link, from the full TIN down to 10 % (VP): removals/s
//   BM_piece_value           the value of one 4096-cell piece (20 points, 190 pairs of Steiner
//                            geodesics): pieces/s and pairs/s
//   BM_grid_mesh             the DEM's full-resolution grid TIN (the kernels' input): cells/s,
//                            and per_Mcell: seconds per million cells (= us per cell)
//   BM_qem_simplify          qem's quadric edge collapse of that TIN to 10 %: cells/s and
//                            per_Mcell (the kernel of dpts-par's default mode, without I/O)
//   BM_qslim                 QSlim (the same kernel with plane quadrics and the outline
//                            locked) of that TIN to 10 %: cells/s and per_Mcell
// (BM_dijkstra_one_source, in bench_geodesic.cpp, is the Steiner-graph Dijkstra per source.)
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <memory>
#include <string>

#include "bench_support.hpp"
#include "core/elimination.hpp"
#include "core/qem.hpp"
#include "core/qslim.hpp"
#include "io/dem_reader.hpp"
#include "parallel/meta.hpp"

namespace {

const std::string kDem = "st_helens_full.tif";

const dpts::io::Dem* load() { return dpts::bench::shared_dem(kDem); }

void BM_importance(benchmark::State& state, dpts::core::Importance kind) {
  const dpts::io::Dem* dem = load();
  if (!dem) return state.SkipWithError(("cannot read " + dpts::bench::shared_path(kDem)).c_str());
  dpts::core::EliminationOptions opt;
  opt.importance = kind;
  dpts::core::Eliminator elim(dem->grid, dem->frame, opt);
  for (auto _ : state) elim.compute_importance(0, elim.vertex_count());
  state.counters["vertices/s"] = benchmark::Counter(
      static_cast<double>(elim.vertex_count()) * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_importance, vp, dpts::core::Importance::vp)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_importance, pld, dpts::core::Importance::pld)->Unit(benchmark::kMillisecond);

void BM_remove_with_update(benchmark::State& state) {
  const dpts::io::Dem* dem = load();
  if (!dem) return state.SkipWithError(("cannot read " + dpts::bench::shared_path(kDem)).c_str());
  std::size_t removals = 0;
  for (auto _ : state) {
    state.PauseTiming();
    auto elim = std::make_unique<dpts::core::Eliminator>(dem->grid, dem->frame,
                                                         dpts::core::EliminationOptions{});
    elim->compute_importance(0, elim->vertex_count());
    const std::size_t before = elim->alive_count();
    state.ResumeTiming();
    elim->eliminate(before / 10, nullptr);
    state.PauseTiming();
    removals += before - elim->alive_count();
    elim.reset();
    state.ResumeTiming();
  }
  state.counters["removals/s"] =
      benchmark::Counter(static_cast<double>(removals), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_remove_with_update)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_piece_value(benchmark::State& state) {
  const dpts::io::Dem* dem = load();
  if (!dem) return state.SkipWithError(("cannot read " + dpts::bench::shared_path(kDem)).c_str());
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  // A 64 x 64 window in the crater: no subsampling.
  dpts::core::HeightGrid window;
  window.width = window.height = 64;
  const int c0 = 140, r0 = 200;
  for (int r = 0; r < 64; ++r) {
    for (int c = 0; c < 64; ++c) window.z.push_back(dem->grid.z[dem->grid.index(c0 + c, r0 + r)]);
  }
  for (auto _ : state) {
    benchmark::DoNotOptimize(dpts::par::piece_value(window, c0, r0, dem->frame, 20, 4096, 1));
  }
  state.counters["pieces/s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["pairs/s"] =
      benchmark::Counter(190.0 * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_piece_value)->Unit(benchmark::kMillisecond);

void cell_counters(benchmark::State& state, std::size_t cells) {
  const double total = static_cast<double>(cells) * static_cast<double>(state.iterations());
  state.counters["cells/s"] = benchmark::Counter(total, benchmark::Counter::kIsRate);
  state.counters["per_Mcell"] =
      benchmark::Counter(total / 1e6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void BM_grid_mesh(benchmark::State& state) {
  const dpts::io::Dem* dem = load();
  if (!dem) return state.SkipWithError(("cannot read " + dpts::bench::shared_path(kDem)).c_str());
  for (auto _ : state) benchmark::DoNotOptimize(dem->grid_mesh());
  cell_counters(state, dem->valid_cells);
}
BENCHMARK(BM_grid_mesh)->Unit(benchmark::kMillisecond);

// The grid TIN of kDem simplified to 10 % by simplify(mesh, keep) each iteration (the copy of
// the TIN untimed).
template <typename Simplify>
void simplify_tin(benchmark::State& state, Simplify&& simplify) {
  const dpts::io::Dem* dem = load();
  if (!dem) return state.SkipWithError(("cannot read " + dpts::bench::shared_path(kDem)).c_str());
  const dpts::core::TriMesh mesh = dem->grid_mesh();
  for (auto _ : state) {
    state.PauseTiming();
    dpts::core::TriMesh copy = mesh;
    state.ResumeTiming();
    benchmark::DoNotOptimize(simplify(std::move(copy), mesh.vertex_count() / 10));
  }
  cell_counters(state, mesh.vertex_count());
}

void BM_qem_simplify(benchmark::State& state) {
  simplify_tin(state, [](dpts::core::TriMesh m, std::size_t keep) {
    return dpts::core::qem_simplify(std::move(m), keep);
  });
}
BENCHMARK(BM_qem_simplify)->Unit(benchmark::kMillisecond);

void BM_qslim(benchmark::State& state) {
  simplify_tin(state, [](dpts::core::TriMesh m, std::size_t keep) {
    return dpts::core::qslim(std::move(m), keep);
  });
}
BENCHMARK(BM_qslim)->Unit(benchmark::kMillisecond);

}  // namespace

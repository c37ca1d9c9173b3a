// BM_simplify_dem: VP and PLD to 10 % on the 770k-cell San Gabriel DEM, in input cells/s.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <string>

#include "bench_support.hpp"
#include "io/dem_reader.hpp"
#include "parallel/simplify.hpp"

namespace {

const std::string kDem = "san_gabriel_bigtujunga_utm11.tif";

const dpts::io::Dem* load() { return dpts::bench::shared_dem(kDem); }

void BM_simplify_dem(benchmark::State& state, dpts::core::Importance kind) {
  const dpts::io::Dem* dem = load();
  if (!dem) {
    state.SkipWithError(("cannot read " + dpts::bench::shared_path(kDem)).c_str());
    return;
  }
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(state.range(0)));
  dpts::core::EliminationOptions opt;
  opt.importance = kind;
  dpts::par::KeepTarget target;
  target.percent = 10.0;
  for (auto _ : state) {
    auto tin = dpts::par::simplify_dem(dem->grid, dem->frame, opt, target, nullptr);
    benchmark::DoNotOptimize(tin.faces.data());
  }
  const double cells = static_cast<double>(dem->grid.cell_count());
  state.counters["cells/s"] =
      benchmark::Counter(cells * state.iterations(), benchmark::Counter::kIsRate);
  // Seconds per million cells = microseconds per cell.
  state.counters["s_per_Mcell"] = benchmark::Counter(
      cells * state.iterations() / 1e6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// 1 and 2 threads, one run each (a run takes seconds), wall and process CPU time.
void settings(benchmark::internal::Benchmark* b) {
  b->Arg(1)
      ->Arg(2)
      ->Unit(benchmark::kSecond)
      ->Iterations(1)
      ->UseRealTime()
      ->MeasureProcessCPUTime();
}
BENCHMARK_CAPTURE(BM_simplify_dem, vp, dpts::core::Importance::vp)->Apply(settings);
BENCHMARK_CAPTURE(BM_simplify_dem, pld, dpts::core::Importance::pld)->Apply(settings);

}  // namespace

BENCHMARK_MAIN();

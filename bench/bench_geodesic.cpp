// BM_dijkstra_one_source: one Dijkstra query (1 source -> 99 targets) on the Steiner graph of a
// 1000 x 1000-cell crop (1M cells) of the Pyrenees SRTM tile, at the default delta.
// BM_anchored_one_source: one anchored search as dpts-eval runs it on T (straight segments
// across faces, bends tracked with waypoints), 1 source -> 99 targets, until all are settled
// (most of the graph).
// BM_straighten_paths: the paths of one anchored search (1 source -> 99 targets, dpts-eval's
// default delta on T) pulled taut (PathStraightener::shortest, as dpts-eval does per pair).
#include <benchmark/benchmark.h>
#include <cpl_conv.h>
#include <gdal_priv.h>

#include <cmath>
#include <memory>
#include <string>

#include "core/geodesic_path.hpp"
#include "core/steiner_graph.hpp"
#include "core/surface_sampling.hpp"
#include "io/dem_reader.hpp"
#include "parallel/evaluate.hpp"

namespace {

const std::string kDem = std::string(DPTS_SHARED_DATA_DIR) + "/pyrenees_srtm3_n42e001.tif";

struct Setup {
  dpts::core::TriMesh mesh;
  std::unique_ptr<dpts::core::SteinerGraph> graph;
  std::unique_ptr<dpts::core::SteinerGraph> straightened;  // at dpts-eval's delta on T
  std::vector<dpts::core::SurfacePoint> points;
};

const Setup* setup() {
  static std::unique_ptr<Setup> s = []() -> std::unique_ptr<Setup> {
    GDALAllRegister();
    CPLSetConfigOption("GDAL_CACHEMAX", "64");
    try {
      const dpts::io::Dem dem = dpts::io::read_dem(kDem, {}, nullptr);
      dpts::core::HeightGrid crop;
      crop.width = crop.height = 1000;
      for (int r = 0; r < 1000; ++r) {
        for (int c = 0; c < 1000; ++c) crop.z.push_back(dem.grid.z[dem.grid.index(c, r)]);
      }
      const auto grid = dpts::core::grid_tin(crop);
      auto out = std::make_unique<Setup>();
      const double m = dem.frame.metres_per_unit;
      for (auto cell : grid.cells) {
        const int c = static_cast<int>(cell % 1000), r = static_cast<int>(cell / 1000);
        out->mesh.xyz.insert(out->mesh.xyz.end(),
                             {m * dem.frame.u(c, r), m * dem.frame.w(c, r), crop.z[cell]});
      }
      out->mesh.faces = grid.faces;
      dpts::core::fix_orientation(out->mesh);
      // note: as dpts-eval orders T's vertices (api/evaluation.cpp).
      dpts::core::order_vertices_spatially(out->mesh);
      const double delta = dpts::par::kDefaultDeltaFactor * dpts::core::mean_edge_length(out->mesh);
      out->graph = std::make_unique<dpts::core::SteinerGraph>(out->mesh, delta);
      out->straightened = std::make_unique<dpts::core::SteinerGraph>(
          out->mesh,
          dpts::par::kStraightenedDeltaFactorDem * dpts::core::mean_edge_length(out->mesh));
      out->straightened->keep_vertex_angles();
      out->points = dpts::core::sample_uniform(out->mesh, 100, 1);
      return out;
    } catch (const std::exception&) {
      return nullptr;
    }
  }();
  return s.get();
}

// The setup, or null with the benchmark marked skipped (the DEM cannot be read).
const Setup* setup_or_skip(benchmark::State& state) {
  const Setup* s = setup();
  if (!s) state.SkipWithError(("cannot read " + kDem).c_str());
  return s;
}

// The targets of the one-source benchmarks: every sample point but the first (the source).
std::vector<dpts::core::SurfacePoint> others(const Setup& s) {
  return {s.points.begin() + 1, s.points.end()};
}

void BM_dijkstra_one_source(benchmark::State& state) {
  const Setup* s = setup_or_skip(state);
  if (!s) return;
  dpts::core::GeodesicQuery query(*s->graph);
  const std::vector<dpts::core::SurfacePoint> targets = others(*s);
  std::vector<double> d;
  for (auto _ : state) {
    query.distances(s->points[0], targets, d);
    benchmark::DoNotOptimize(d.data());
  }
  const double nodes = static_cast<double>(s->graph->node_count());
  state.counters["graph_nodes"] = nodes;
  state.counters["buckets"] = query.uses_buckets() ? 1 : 0;
  state.counters["min_seg_m"] = s->graph->min_segment();
  state.counters["max_seg_m"] = s->graph->max_segment();
  state.counters["nodes/s"] =
      benchmark::Counter(nodes * state.iterations(), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_dijkstra_one_source)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_anchored_one_source(benchmark::State& state) {
  const Setup* s = setup_or_skip(state);
  if (!s) return;
  dpts::core::GeodesicQuery query(*s->straightened);
  query.set_anchored(true);
  query.set_track_bends(true, 2 * s->straightened->max_segment());
  const std::vector<dpts::core::SurfacePoint> targets = others(*s);
  std::vector<double> d;
  double sum = 0;
  for (auto _ : state) {
    query.distances(s->points[0], targets, d);
    for (double x : d) sum += x;
    benchmark::DoNotOptimize(sum);
  }
  const double nodes = static_cast<double>(query.settled());
  state.counters["settled"] = nodes;
  // note: kInvert of a rate: seconds per settled node.
  state.counters["s/node"] =
      benchmark::Counter(nodes * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_anchored_one_source)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_straighten_paths(benchmark::State& state) {
  const Setup* s = setup_or_skip(state);
  if (!s) return;
  dpts::core::GeodesicQuery query(*s->straightened);
  query.set_anchored(true);
  const std::vector<dpts::core::SurfacePoint> targets = others(*s);
  std::vector<double> d;
  query.distances(s->points[0], targets, d);
  dpts::core::PathStraightener straightener(*s->straightened);
  double sum = 0;
  for (auto _ : state) {
    sum = 0;
    for (std::size_t j = 0; j < targets.size(); ++j) {
      sum += straightener.shortest(query, s->points[0], j, targets[j], d[j]);
    }
    benchmark::DoNotOptimize(sum);
  }
  const auto& st = straightener.stats();
  const double runs = static_cast<double>(state.iterations());
  state.counters["paths"] = static_cast<double>(st.paths) / runs;
  state.counters["passes"] = static_cast<double>(st.passes) / runs;
  state.counters["reroutes"] = static_cast<double>(st.reroutes) / runs;
  state.counters["mean_m"] = sum / static_cast<double>(targets.size());
}
BENCHMARK(BM_straighten_paths)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace

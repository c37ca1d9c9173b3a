// The distance-preserving error: zero for identical meshes, same for any thread count.
#include "parallel/evaluate.hpp"

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/steiner_graph.hpp"
#include "core/surface_sampling.hpp"
#include "parallel/memory.hpp"
#include "parallel/simplify.hpp"
#include "test_support.hpp"

using namespace dpts;

namespace {

core::HeightGrid hills() {
  return test::make_grid(36, 28, [](int c, int r) {
    if (std::hypot(c - 20.0, r - 12.0) < 3.0) return std::nan("");
    return 60.0 * std::sin(c * 0.3) * std::cos(r * 0.2) + 2.0 * r;
  });
}

// A TIN over grid g in metres (10 m cells): the grid TIN, or a simplification of it.
core::TriMesh to_mesh(const core::HeightGrid& g, const std::vector<std::uint32_t>& cells,
                      const std::vector<std::array<std::uint32_t, 3>>& faces) {
  core::TriMesh m;
  for (auto c : cells)
    m.xyz.insert(m.xyz.end(), {10.0 * (c % g.width), -10.0 * (c / g.width), g.z[c]});
  m.faces = faces;
  core::fix_orientation(m);
  return m;
}

core::TriMesh simplified(const core::HeightGrid& g, double percent) {
  const double j[2][2] = {{10, 0}, {0, -10}};
  par::KeepTarget target;
  target.percent = percent;
  const auto tin = par::simplify_dem(g, core::GridFrame::from_jacobian(j), {}, target, nullptr);
  return to_mesh(g, tin.cells, tin.faces);
}

// The grid TIN of hills() in metres.
core::TriMesh hills_grid_mesh(const core::HeightGrid& g) {
  const auto grid = core::grid_tin(g);
  return to_mesh(g, grid.cells, grid.faces);
}

// Evaluation options: K points per set, and sets.
par::EvalOptions eval_options(int points, int sets) {
  par::EvalOptions o;
  o.points = points;
  o.sets = sets;
  return o;
}

// T and T' of most tests: the grid TIN of hills() and its 20 % simplification.
std::pair<core::TriMesh, core::TriMesh> hills_and_20_percent() {
  const auto g = hills();
  return {hills_grid_mesh(g), simplified(g, 20.0)};
}

}  // namespace

TEST_CASE("a mesh identical to the DEM grid has distance error 0", "[parallel][evaluate]") {
  const auto g = hills();
  const auto t = hills_grid_mesh(g);
  const auto opt = eval_options(20, 2);
  const auto r = par::evaluate_distances(t, t, opt);
  CHECK(r.set_errors.size() == 2);
  CHECK(r.distance_error == 0.0);
  // The engine's unsimplified TIN is the same grid TIN: error 0 up to rounding.
  const auto r100 = par::evaluate_distances(t, simplified(g, 100.0), opt);
  CHECK(r100.distance_error < 1e-12);
}

TEST_CASE("a mesh identical to a DEM with no hole measures 0, its searches meeting",
          "[parallel][evaluate]") {
  // With no hole the searches meet in the middle, on both meshes with radii scaled from the
  // same guess: the same searches, the same distances.
  const auto g = test::make_grid(
      30, 24, [](int c, int r) { return 60.0 * std::sin(c * 0.3) * std::cos(r * 0.2) + 2.0 * r; });
  const auto t = hills_grid_mesh(g);
  const auto r = par::evaluate_distances(t, t, eval_options(30, 2));
  // note: a met pair whose route (its earlier half told by its bends, seen from above) passes a
  // vertex on the other side of its path pulls taut longer than the path: measured one way
  // (here 1 of the 435 on each mesh, as the anchored labels round to floats), on both meshes.
  CHECK(r.original_one_way <= 2);
  CHECK(r.simplified_one_way == r.original_one_way);
  CHECK(r.distance_error < 1e-12);
}

TEST_CASE("a mesh keeping T's surface measures about 0: shortened routes go back to T",
          "[parallel][evaluate]") {
  // A square pyramid whose apex lies off the cell centres: its ridges cross the grid's cells,
  // the grid TIN's vertices beside them are saddles (total angle above 2 pi), round either side
  // of which a path may be locally shortest. Its VP 10 % mesh keeps the surface exactly.
  const auto g = test::make_grid(101, 101, [](int c, int r) {
    return 1000.0 - 8.0 * std::max(std::fabs(c - 50.3), std::fabs(r - 49.7));
  });
  const auto t = hills_grid_mesh(g);
  const auto s = simplified(g, 10.0);
  REQUIRE(s.vertex_count() < t.vertex_count() / 5);
  const auto r = par::evaluate_distances(t, s, eval_options(30, 1));
  // note: with the routes of T tried on T' alone, as before, 2.4e-6: 5 of the 435 pairs ended
  // round the wrong side of a saddle on one mesh, up to 6e-4 long (one of them on T').
  CHECK(r.distance_error < 1e-9);
}

TEST_CASE("the distance error grows as fewer vertices are kept", "[parallel][evaluate]") {
  const auto g = hills();
  const auto t = hills_grid_mesh(g);
  const auto opt = eval_options(25, 2);
  const double e50 = par::evaluate_distances(t, simplified(g, 50.0), opt).distance_error;
  const double e10 = par::evaluate_distances(t, simplified(g, 10.0), opt).distance_error;
  CHECK(e50 > 0);
  CHECK(e10 > e50);
}

TEST_CASE("the default spacing follows each mesh's edges, the paper's distances share T's",
          "[parallel][evaluate]") {
  const auto [t, s] = hills_and_20_percent();
  auto opt = eval_options(6, 1);
  const double edge_t = core::mean_edge_length(t), edge_s = core::mean_edge_length(s);
  REQUIRE(edge_s > 1.5 * edge_t);  // a 20 % TIN has longer edges
  const auto straightened = par::evaluate_distances(t, s, opt);
  CHECK(straightened.delta_m == par::kStraightenedDeltaFactorDem * edge_t);
  CHECK(straightened.delta_mesh_m == par::kStraightenedDeltaFactor * edge_s);
  // Never finer on T' than on T: T itself as the mesh gets T's spacing.
  const auto itself = par::evaluate_distances(t, t, opt);
  CHECK(itself.delta_mesh_m == itself.delta_m);
  CHECK(straightened.simplified_nodes ==
        core::SteinerGraph(s, straightened.delta_mesh_m).node_count());
  opt.straighten = false;
  const auto steiner = par::evaluate_distances(t, s, opt);
  CHECK(steiner.delta_m == par::kDefaultDeltaFactor * edge_t);
  CHECK(steiner.delta_mesh_m == steiner.delta_m);
  opt.straighten = true;
  opt.delta_m = 7.5;
  const auto given = par::evaluate_distances(t, s, opt);
  CHECK(given.delta_m == 7.5);
  CHECK(given.delta_mesh_m == 7.5);
}

TEST_CASE("evaluation figures are identical for 1 and 2 threads",
          "[parallel][evaluate][determinism]") {
  const auto [t, s] = hills_and_20_percent();
  const auto opt = eval_options(30, 3);
  std::vector<double> errors[2];
  for (int threads = 1; threads <= 2; ++threads) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism,
                          static_cast<std::size_t>(threads));
    errors[threads - 1] = par::evaluate_distances(t, s, opt).set_errors;
  }
  CHECK(errors[0] == errors[1]);
}

TEST_CASE("sample points outside the mesh are an error with their count", "[parallel][evaluate]") {
  const auto g = hills();
  const auto t = hills_grid_mesh(g);
  // A mesh covering only the western half of the DEM.
  core::TriMesh half = t;
  half.faces.clear();
  for (const auto& f : t.faces) {
    if (t.xyz[3 * f[0]] < 170 && t.xyz[3 * f[1]] < 170 && t.xyz[3 * f[2]] < 170)
      half.faces.push_back(f);
  }
  const auto opt = eval_options(40, 3);
  CHECK_THROWS_WITH(
      par::evaluate_distances(t, half, opt),
      Catch::Matches(".*[0-9]+ of 40 sample points of set 1 lie outside the mesh's footprint"));
}

TEST_CASE("meeting in the middle gives the distances of one-way queries",
          "[parallel][evaluate][geodesic]") {
  // Hills with a no-data hole (paths bend around it), on the grid TIN and on a 20 % TIN.
  const auto g = hills();
  for (const auto& mesh : {hills_grid_mesh(g), simplified(g, 20.0)}) {
    const core::SteinerGraph graph(mesh, 0.25 * core::mean_edge_length(hills_grid_mesh(g)));
    const auto points = core::sample_uniform(mesh, 40, 5);
    par::PairwiseStats meet_stats, one_way_stats;
    par::PairwiseOptions steiner, one_way;
    steiner.straighten = one_way.straighten = false;
    one_way.method = par::PairwiseMethod::kOneWay;
    const auto meet = par::pairwise_distances(graph, points, steiner, &meet_stats);
    const auto ref = par::pairwise_distances(graph, points, one_way, &one_way_stats);
    const std::size_t k = points.size();
    for (std::size_t i = 0; i < k; ++i) {
      for (std::size_t j = i + 1; j < k; ++j) {
        CAPTURE(i, j);
        REQUIRE(std::isfinite(ref[i * k + j]));
        CHECK(meet[i * k + j] == Approx(ref[i * k + j]).epsilon(1e-12));
      }
    }
    // The searches met for most pairs, and searched less of the graph in all.
    CHECK(meet_stats.one_way_pairs < k * (k - 1) / 4);
    CHECK(one_way_stats.one_way_pairs == k * (k - 1) / 2);
    CHECK(meet_stats.settled < one_way_stats.settled);
  }
}

TEST_CASE("straightened, meeting in the middle measures what one-way searches measure",
          "[parallel][evaluate][geodesic]") {
  // Hills with a no-data hole, on the grid TIN and on a 20 % TIN, at the default spacing: each
  // met pair's path runs through the meeting node, the earlier search's half told by its bends
  // and waypoints; pulled taut, it is the geodesic the one-way search's path gives.
  const auto g = hills();
  for (const auto& mesh : {hills_grid_mesh(g), simplified(g, 20.0)}) {
    const core::SteinerGraph graph(
        mesh, par::kStraightenedDeltaFactorDem * core::mean_edge_length(hills_grid_mesh(g)));
    const auto points = core::sample_uniform(mesh, 40, 5);
    par::PairwiseStats meet_stats, one_way_stats;
    par::PairwiseOptions meet, one_way;
    one_way.method = par::PairwiseMethod::kOneWay;
    par::PairRoutes routes;
    meet.routes_out = &routes;
    const auto d = par::pairwise_distances(graph, points, meet, &meet_stats);
    const auto ref = par::pairwise_distances(graph, points, one_way, &one_way_stats);
    const std::size_t k = points.size();
    double sum = 0;
    std::size_t same = 0;
    for (std::size_t i = 0; i < k; ++i) {
      for (std::size_t j = i + 1; j < k; ++j) {
        CAPTURE(i, j);
        REQUIRE(std::isfinite(ref[i * k + j]));
        REQUIRE(std::isfinite(d[i * k + j]));
        CHECK(d[i * k + j] == Approx(ref[i * k + j]).epsilon(1e-3));
        sum += d[i * k + j] / ref[i * k + j] - 1;
        same += std::fabs(d[i * k + j] / ref[i * k + j] - 1) < 1e-9;
        // Its route, for the other mesh: ends at point j.
        std::vector<std::array<double, 2>> bends, taut;
        REQUIRE(routes.get(i, j, bends, taut));
        REQUIRE_FALSE(bends.empty());
        CHECK(bends.back()[0] ==
              routes.origin()[0] + static_cast<float>(points[j].x - routes.origin()[0]));
      }
    }
    const double pairs = static_cast<double>(k * (k - 1) / 2);
    CAPTURE(sum / pairs, same);
    CHECK(std::fabs(sum / pairs) < 1e-5);
    CHECK(same > 0.9 * pairs);
    // The searches met for most pairs. note: on a grid this small the radii cover most of it;
    // on San Gabriel's T each search settles about 36 % of the graph, one way 72 %.
    CHECK(meet_stats.one_way_pairs < k * (k - 1) / 4);
    CHECK(meet_stats.straighten_failed == 0);
    // Every path straightened took a pass at least; on hills, some were rerouted round a vertex.
    CHECK(meet_stats.straighten_passes >= meet_stats.straightened);
    CHECK(meet_stats.reroutes > 0);
  }
}

TEST_CASE("meeting radii scaled from an estimate: the same distances, fewer nodes searched",
          "[parallel][evaluate][geodesic]") {
  // The pairs' distances on another surface (dpts-eval gives T's searches a guess from T') set
  // the meeting radii instead of pilots searched in full and straight-line distances. A good
  // estimate searches less; a wrong one (half the distances) leaves pairs to one-way searches:
  // slower, the same distances; an unusable one (not finite) is not used.
  const auto g = hills();
  const auto mesh = hills_grid_mesh(g);
  const auto points = core::sample_uniform(mesh, 40, 5);
  const std::size_t k = points.size();
  for (const bool straighten : {false, true}) {
    CAPTURE(straighten);
    const double factor = straighten ? par::kStraightenedDeltaFactorDem : 0.25;
    const core::SteinerGraph graph(mesh, factor * core::mean_edge_length(mesh));
    par::PairwiseOptions options;
    options.straighten = straighten;
    par::PairwiseStats ref_stats;
    const auto ref = par::pairwise_distances(graph, points, options, &ref_stats);
    std::vector<double> good(ref), half(ref), broken(ref);
    for (auto& d : good) d *= 1.003;
    for (auto& d : half) d *= 0.5;
    broken[1] = std::numeric_limits<double>::infinity();
    std::vector<par::PairwiseStats> stats(3);
    std::vector<std::vector<double>> got;
    for (const auto* estimate : {&good, &half, &broken}) {
      options.estimate = estimate;
      got.push_back(par::pairwise_distances(graph, points, options, &stats[got.size()]));
    }
    for (std::size_t e = 0; e < got.size(); ++e) {
      std::size_t same = 0;
      for (std::size_t i = 0; i < k; ++i) {
        for (std::size_t j = i + 1; j < k; ++j) {
          CAPTURE(e, i, j);
          REQUIRE(std::isfinite(ref[i * k + j]));
          CHECK(got[e][i * k + j] == Approx(ref[i * k + j]).epsilon(straighten ? 1e-3 : 1e-12));
          same += std::fabs(got[e][i * k + j] / ref[i * k + j] - 1) < 1e-9;
        }
      }
      CHECK(same > 0.9 * static_cast<double>(k * (k - 1) / 2));
    }
    CHECK(stats[0].settled < ref_stats.settled);
    CHECK(stats[0].one_way_pairs < k * (k - 1) / 20);
    CHECK(stats[1].one_way_pairs > ref_stats.one_way_pairs);
    CHECK(stats[2].settled == ref_stats.settled);
    CHECK(got[2] == ref);
  }
}

TEST_CASE("a memory budget bounds the searches at once, with the same figures",
          "[parallel][evaluate][memory]") {
  const auto [t, s] = hills_and_20_percent();
  auto opt = eval_options(30, 1);
  opt.straighten = false;  // meeting in the middle: a finished search waits for its joins
  tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
  const auto free_run = par::evaluate_distances(t, s, opt);
  CHECK(free_run.max_searches == 0);
  REQUIRE(free_run.search_bytes > 0);
  // Graphs and two searches on T: one worker, one finished search waiting for its joins.
  opt.memory_budget_bytes =
      free_run.graphs_bytes + 2 * free_run.search_bytes + free_run.pairs_bytes;
  const auto two = par::evaluate_distances(t, s, opt);
  CHECK(two.max_searches == 2);
  CHECK(two.set_errors == free_run.set_errors);
  // Plenty: 3 per thread less one.
  opt.memory_budget_bytes = free_run.graphs_bytes + 100 * free_run.search_bytes;
  CHECK(par::evaluate_distances(t, s, opt).max_searches == 5);
  // One search short.
  opt.memory_budget_bytes =
      free_run.graphs_bytes + 2 * free_run.search_bytes + free_run.pairs_bytes - 1;
  CHECK_THROWS_AS(par::evaluate_distances(t, s, opt), InputError);
  CHECK_THROWS_WITH(
      par::evaluate_distances(t, s, opt),
      Catch::Matches("the geodesics need about .* \\(a Steiner graph of .*, 2 searches of "
                     ".*, the pairs' arrays .*\\), more than the .* available "
                     "\\(--max-memory\\); use a larger --delta or fewer --points"));
  // Straightened, a search holds more than twice the memory: one per thread at most.
  opt.straighten = true;
  opt.memory_budget_bytes = 0;
  const auto straightened = par::evaluate_distances(t, s, opt);
  opt.memory_budget_bytes = straightened.graphs_bytes + 100 * straightened.search_bytes;
  const auto plenty = par::evaluate_distances(t, s, opt);
  CHECK(plenty.max_searches == 2);
  CHECK(plenty.set_errors == straightened.set_errors);
  CHECK(plenty.original_one_way == 30 * 29 / 2);  // the hole: one way (see below)
  // Room for one search only: measured one way, one search at a time.
  opt.memory_budget_bytes =
      straightened.graphs_bytes + 3 * straightened.search_bytes / 2 + straightened.pairs_bytes;
  const auto one = par::evaluate_distances(t, s, opt);
  CHECK(one.max_searches == 1);
  CHECK(one.original_one_way == 30 * 29 / 2);
  CHECK(one.distance_error == Approx(straightened.distance_error).epsilon(0.05));
}

TEST_CASE("the searches held at once follow --threads (a global_control), not the cores alone",
          "[parallel][evaluate][memory]") {
  // The paper's distances: up to three searches a thread at once, less one. At --threads 1 on
  // a machine of more cores, those of one thread (they were counted per core).
  const auto [t, s] = hills_and_20_percent();
  auto opt = eval_options(10, 1);
  opt.straighten = false;
  opt.memory_budget_bytes = std::size_t{1} << 34;  // ample: the threads bound it
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    CHECK(par::worker_threads() == 1);
    CHECK(par::evaluate_distances(t, s, opt).max_searches == 2);
  }
  const std::size_t threads = par::worker_threads();
  CHECK(threads == static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
  CHECK(par::evaluate_distances(t, s, opt).max_searches == 3 * threads - 1);
}

TEST_CASE("the graph estimate counts the nodes of the graph", "[parallel][evaluate][memory]") {
  const auto g = hills();
  for (const auto& mesh : {hills_grid_mesh(g), simplified(g, 20.0)}) {
    for (double delta : {2.0, 5.0, 20.0}) {
      CAPTURE(delta);
      const core::SteinerGraph graph(mesh, delta);
      const auto est = core::SteinerGraph::estimate(mesh, delta);
      CHECK(est.nodes == graph.node_count());
      CHECK(est.bytes > 32 * graph.node_count());
    }
  }
}

TEST_CASE("pairwise distances with a bound on searches give the same distances",
          "[parallel][evaluate][memory]") {
  const auto g = hills();
  const auto t = hills_grid_mesh(g);
  const core::SteinerGraph graph(t, 0.25 * core::mean_edge_length(t));
  const auto points = core::sample_uniform(t, 25, 9);
  tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
  par::PairwiseOptions steiner;  // meeting in the middle (Steiner distances only)
  steiner.straighten = false;
  const auto free_run = par::pairwise_distances(graph, points, steiner);
  par::PairwiseOptions bounded = steiner;
  for (std::size_t bound : {2, 3, 4}) {
    CAPTURE(bound);
    bounded.max_searches = bound;
    CHECK(par::pairwise_distances(graph, points, bounded) == free_run);
  }
  bounded.max_searches = 1;
  CHECK_THROWS_AS(par::pairwise_distances(graph, points, bounded), std::invalid_argument);
  bounded.method = par::PairwiseMethod::kOneWay;
  const auto one_way = par::pairwise_distances(graph, points, bounded);
  CHECK(one_way.size() == free_run.size());
  // Straightened meeting too: which searches wait at once changes nothing.
  par::PairwiseOptions straightened;
  const auto free_straightened = par::pairwise_distances(graph, points, straightened);
  for (std::size_t bound : {2, 3, 5}) {
    CAPTURE(bound);
    straightened.max_searches = bound;
    CHECK(par::pairwise_distances(graph, points, straightened) == free_straightened);
  }
}

TEST_CASE("progress tells each stage as it starts and the sources searched in geodesic stages",
          "[parallel][evaluate][progress]") {
  const auto [t, s] = hills_and_20_percent();
  const auto opt = eval_options(12, 2);
  tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
  // note: no lock: the reports are serialized by contract (the TSan build checks it).
  std::vector<std::pair<std::string, double>> calls;
  par::evaluate_distances(t, s, opt, [&](double fraction, std::string_view stage) {
    calls.emplace_back(std::string(stage), fraction);
    return true;
  });
  std::vector<std::string> stages;
  for (const auto& [stage, fraction] : calls) {
    if (fraction == 0) stages.push_back(stage);
  }
  // One mesh at a time, T' first: its graph, its sets; then T's; then T' again for the routes
  // found on T; then, while a round shortened some pair, at most 3 rounds more, by turns on T
  // and T', for the routes the last round shortened.
  REQUIRE(stages.size() >= 9);
  REQUIRE(stages.size() <= 18);
  REQUIRE(stages.size() % 3 == 0);
  CHECK(stages[0].rfind("Steiner graph of T': ", 0) == 0);
  CHECK(stages[1] == "set 1/2: geodesics on T'");
  CHECK(stages[2] == "set 2/2: geodesics on T'");
  CHECK(stages[3].rfind("Steiner graph of T: ", 0) == 0);
  CHECK(stages[4] == "set 1/2: geodesics on T");
  CHECK(stages[5] == "set 2/2: geodesics on T");
  CHECK(stages[6].rfind("Steiner graph of T': ", 0) == 0);
  CHECK(stages[7] == "set 1/2: routes of T on T'");
  CHECK(stages[8] == "set 2/2: routes of T on T'");
  for (std::size_t round = 1; 3 * round + 6 < stages.size(); ++round) {
    const bool on_t = round % 2 == 1;
    const std::string routes = on_t ? ": routes of T' on T" : ": routes of T on T'";
    const std::string again = round > 1 ? " again" : "";
    CHECK(stages[3 * round + 6].rfind(on_t ? "Steiner graph of T: " : "Steiner graph of T': ", 0) ==
          0);
    CHECK(stages[3 * round + 7] == "set 1/2" + routes + again);
    CHECK(stages[3 * round + 8] == "set 2/2" + routes + again);
  }
  // Each geodesic stage: its start, then one report per source, 1/12 to 12/12 in order.
  std::size_t i = 0;
  while (i < calls.size() && calls[i].second == 0) {
    const std::string stage = calls[i++].first;
    // A graph's stage, or the routes': no sources searched.
    if (stage.rfind("Steiner graph of ", 0) == 0 ||
        stage.find(": routes of ") != std::string::npos) {
      continue;
    }
    for (int n = 1; n <= 12; ++n, ++i) {
      REQUIRE(i < calls.size());
      CHECK(calls[i].first == stage);
      CHECK(calls[i].second == Approx(n / 12.0));
    }
  }
  CHECK(i == calls.size());
}

TEST_CASE("progress answering false during a geodesic stage stops the run at its end",
          "[parallel][evaluate][progress]") {
  const auto g = hills();
  const auto t = hills_grid_mesh(g);
  const auto opt = eval_options(12, 2);
  int searches = 0;
  CHECK_THROWS_AS(par::evaluate_distances(t, t, opt,
                                          [&](double fraction, std::string_view) {
                                            if (fraction > 0) ++searches;
                                            return fraction == 0;
                                          }),
                  Cancelled);
  CHECK(searches == 12);  // the first geodesic stage's searches, none after it
}

// PLD'/VP' as a parallel, out-of-core engine (see meta.hpp).
#include "parallel/meta.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "core/footprint.hpp"
#include "core/merge.hpp"
#include "core/piece_budget.hpp"
#include "core/surface_sampling.hpp"
#include "parallel/evaluate.hpp"
#include "parallel/memory.hpp"
#include "parallel/piece_support.hpp"

namespace dpts::par {
namespace {

std::uint64_t piece_seed(std::uint64_t seed, std::size_t piece) {
  std::uint64_t h = (seed + 0x9E3779B97F4A7C15ull) * 0xBF58476D1CE4E5B9ull;
  h ^= (piece + 1) * 0x94D049BB133111EBull;
  return h ^ (h >> 31);
}

// One streaming pass over the raster in strips of whole rows: surface vertices per block.
core::BlockCounts count_blocks(const core::RasterSource& dem, std::size_t strip_bytes,
                               const core::Progress& progress, std::size_t* valid_cells,
                               std::size_t* absurd_cells, core::UsualNoDataCounts* usual) {
  core::BlockCounts bc;
  bc.width = dem.width();
  bc.height = dem.height();
  bc.block = 16;
  auto blocks = [&](int b) {
    return static_cast<double>((dem.width() + b - 1) / b) * ((dem.height() + b - 1) / b);
  };
  while (blocks(bc.block) > double(1 << 20)) bc.block *= 2;
  bc.blocks_x = (dem.width() + bc.block - 1) / bc.block;
  bc.blocks_y = (dem.height() + bc.block - 1) / bc.block;
  bc.counts.assign(static_cast<std::size_t>(bc.blocks_x) * bc.blocks_y, 0);
  bc.outline.assign(bc.counts.size(), 0);
  // Strips of whole blocks of the raster (GDAL reads whole blocks anyway) and of whole count
  // blocks (so that no two strips count into one block), read concurrently: as many strips as
  // threads at once within the budget, and at least 4 a thread where the raster has the rows.
  const std::size_t row_bytes = static_cast<std::size_t>(dem.width()) * sizeof(double);
  const std::size_t threads = worker_threads();
  const int unit = std::lcm(std::max(1, dem.block_height()), bc.block);
  int strip = static_cast<int>(std::max<std::size_t>(1, strip_bytes / threads / row_bytes));
  strip = std::min(
      strip, (dem.height() + static_cast<int>(4 * threads) - 1) / static_cast<int>(4 * threads));
  strip = std::max(unit, strip / unit * unit);
  const int strips = (dem.height() + strip - 1) / strip;
  std::vector<std::size_t> valid_of(static_cast<std::size_t>(strips), 0);
  std::vector<core::RasterSource::Implausible> implausible_of(static_cast<std::size_t>(strips));
  // Counts rows [r0, r1) of strip k from the rows [a, b) that hold them.
  auto count_strip = [&](std::size_t k, int a, int b, int r0, int r1) {
    core::RasterSource::Implausible& implausible = implausible_of[k];
    implausible.row0 = r0;
    implausible.row1 = r1;
    const core::HeightGrid g = dem.read(0, a, dem.width(), b - a, &implausible);
    std::size_t valid = 0;
    const auto own_end = g.z.begin() + static_cast<std::ptrdiff_t>(g.index(0, r1 - a));
    for (auto z = g.z.begin() + static_cast<std::ptrdiff_t>(g.index(0, r0 - a)); z != own_end;
         ++z) {
      valid += std::isnan(*z) ? 0 : 1;
    }
    valid_of[k] = valid;
    // note: a strip of no-data has no surface vertex: not searched (8e8 no-data cells of a
    // dense DEFLATE GeoTIFF: about 15 % off the count).
    if (valid == 0) return;
    // Whether the cell at (col, row of g) is no-data (false outside the raster: its sides
    // are straight runs of the outline, which a collapse simplifies).
    auto void_at = [&](int col, int row) {
      return col >= 0 && col < g.width && row >= 0 && row < g.height &&
             std::isnan(g.z[g.index(col, row)]);
    };
    for (std::uint32_t cell : core::surface_cells(g)) {
      const int gr = static_cast<int>(cell / static_cast<std::uint32_t>(g.width));
      const int row = gr + a;
      const int col = static_cast<int>(cell % static_cast<std::uint32_t>(g.width));
      if (row < r0 || row >= r1) continue;
      const std::size_t block =
          static_cast<std::size_t>(row / bc.block) * bc.blocks_x + col / bc.block;
      ++bc.counts[block];
      // note: the strip's rows and one more each side are in g (a row off g is off the raster).
      if (void_at(col - 1, gr) || void_at(col + 1, gr) || void_at(col, gr - 1) ||
          void_at(col, gr + 1))
        ++bc.outline[block];
    }
  };
  std::mutex report;
  std::size_t rows_done = 0;
  std::atomic<bool> stop{false};
  // note: grain 1, in order where one thread runs them (the progress then as before).
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, static_cast<std::size_t>(strips), 1),
      [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t k = range.begin(); k < range.end(); ++k) {
          if (stop) return;
          const int r0 = static_cast<int>(k) * strip;
          const int r1 = std::min(dem.height(), r0 + strip);
          // One row more on each side: whether a cell is a surface vertex depends on its
          // neighbours.
          const int a = std::max(0, r0 - 1), b = std::min(dem.height(), r1 + 1);
          // note: a region GDAL knows to be empty (a sparse file's unwritten blocks) is not
          // read: a raster of 70000 x 70000 cells, no-data but for a small window, is counted
          // in seconds.
          if (!dem.empty(0, a, dem.width(), b - a)) count_strip(k, a, b, r0, r1);
          if (progress) {
            std::lock_guard<std::mutex> hold(report);
            rows_done += static_cast<std::size_t>(r1 - r0);
            if (!stop && !progress(static_cast<double>(rows_done) / dem.height(), "count")) {
              stop = true;
            }
          }
        }
      },
      tbb::simple_partitioner());
  if (stop) throw Cancelled();
  *valid_cells = 0;
  std::size_t absurd = 0;
  for (std::size_t k = 0; k < valid_of.size(); ++k) {
    *valid_cells += valid_of[k];
    absurd += implausible_of[k].cells;
    for (std::size_t v = 0; v < usual->size(); ++v) (*usual)[v] += implausible_of[k].usual[v];
  }
  *absurd_cells = absurd;
  return bc;
}

// What a piece hands to the merge: the own vertices it kept after going `tail` removals
// beyond its budget, those last removals in order (so the merge can take back any number of
// them), and the outline edges touching own vertices at the deepest state.
struct PieceOutput {
  std::vector<std::uint32_t> cells;
  std::vector<double> z;
  std::vector<core::OutlineEdge> outline;
  std::vector<core::Removal> tail;
  std::vector<double> tail_z;
  std::size_t kept_at_budget = 0;
};

// A piece's window: the piece with `halo` cells of context round it, clipped to the raster
// (columns wc0..wc1 - 1, rows wr0..wr1 - 1), and the piece's own cells inside it (window-local
// columns oc0..oc1 - 1, rows or0..or1 - 1).
struct PieceWindow {
  int wc0, wr0, wc1, wr1, ww, wh;
  int oc0, or0, oc1, or1;
  PieceWindow(const core::RasterSource& dem, const core::Piece& p, int halo)
      : wc0(std::max(0, p.col0 - halo)),
        wr0(std::max(0, p.row0 - halo)),
        wc1(std::min(dem.width(), p.col0 + p.width + halo)),
        wr1(std::min(dem.height(), p.row0 + p.height + halo)),
        ww(wc1 - wc0),
        wh(wr1 - wr0),
        oc0(p.col0 - wc0),
        or0(p.row0 - wr0),
        oc1(oc0 + p.width),
        or1(or0 + p.height) {}
  bool own(int c, int r) const { return c >= oc0 && c < oc1 && r >= or0 && r < or1; }
};

// The elimination's options for a piece's window: the context pinned (triangulated, never
// removed), the own outline cells next to another piece pinned too, and the chords kept inside
// the window where other pieces' cells lie beyond it.
core::EliminationOptions piece_options(const core::RasterSource& dem, const core::HeightGrid& grid,
                                       const PieceWindow& w, const MetaOptions& options) {
  const int wc0 = w.wc0, wr0 = w.wr0, wc1 = w.wc1, wr1 = w.wr1, ww = w.ww, wh = w.wh;
  const int oc0 = w.oc0, or0 = w.or0, oc1 = w.oc1, or1 = w.or1;
  auto own = [&](int c, int r) { return w.own(c, r); };
  core::EliminationOptions eo = options.elimination;
  eo.pinned.assign(grid.z.size(), 0);
  for (int r = 0; r < wh; ++r) {
    for (int c = 0; c < ww; ++c) {
      std::uint8_t& pin = eo.pinned[grid.index(c, r)];
      if (!own(c, r)) {
        pin = 1;
        continue;
      }
      if (c != oc0 && c != oc1 - 1 && r != or0 && r != or1 - 1) continue;
      // An own outline cell next to another piece: the outline may run on into that piece,
      // where only that piece knows which cells stay. Keep it, so that every chord the merged
      // TIN has was checked by the one piece that owns both its ends.
      bool outline = false, foreign = false;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int gc = wc0 + c + dc, gr = wr0 + r + dr;
          const bool in_raster = gc >= 0 && gr >= 0 && gc < dem.width() && gr < dem.height();
          if (!in_raster || !grid.is_valid(c + dc, r + dr)) outline = true;
          if (in_raster && !own(c + dc, r + dr)) foreign = true;
        }
      }
      if (outline && foreign) pin = 1;
    }
  }
  // Beyond the window's sides lie other pieces' cells, except where the raster ends. (A piece
  // that is the whole raster has no neighbour to be merged with: no box.)
  const double inf = std::numeric_limits<double>::infinity();
  if (wc0 > 0 || wr0 > 0 || wc1 < dem.width() || wr1 < dem.height()) {
    eo.chord_box =
        core::EliminationOptions::Box{wc0 == 0 ? -inf : 0.0, wc1 == dem.width() ? inf : ww - 1.0,
                                      wr0 == 0 ? -inf : 0.0, wr1 == dem.height() ? inf : wh - 1.0};
  }
  eo.outline_chord_ok = dem.outline_chord_test(wc0, wr0, ww);
  return eo;
}

// Reads a piece with its context, simplifies it to `budget` own vertices, and returns the
// own vertices it kept and the outline edges that touch them (raster cell indices).
PieceOutput simplify_piece(const core::RasterSource& dem, const core::Piece& p, std::size_t budget,
                           const MetaOptions& options, PieceReport& report,
                           const core::Progress& progress) {
  const PieceWindow w(dem, p, std::max(2, options.halo));
  const int wc0 = w.wc0, wr0 = w.wr0, ww = w.ww;
  core::HeightGrid grid = read_window(dem, wc0, wr0, ww, w.wh, report.read_s);
  const auto t0 = std::chrono::steady_clock::now();
  auto own = [&](int c, int r) { return w.own(c, r); };
  const core::EliminationOptions eo = piece_options(dem, grid, w, options);
  core::Eliminator elim(grid, dem.frame(), eo);
  const auto& cells = elim.cells();
  auto own_cell = [&](std::uint32_t cell) {
    return own(static_cast<int>(cell % static_cast<std::uint32_t>(ww)),
               static_cast<int>(cell / static_cast<std::uint32_t>(ww)));
  };
  std::size_t own_count = 0;
  for (std::uint32_t cell : cells) own_count += own_cell(cell) ? 1 : 0;
  if (own_count != p.vertices) {
    throw std::logic_error("piece at column " + std::to_string(p.col0) + ", row " +
                           std::to_string(p.row0) + " has " + std::to_string(own_count) +
                           " surface vertices, the count pass found " + std::to_string(p.vertices));
  }
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size(), 2048),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        elim.compute_importance(r.begin(), r.end());
                      });
  });
  const std::size_t context = cells.size() - own_count;
  elim.eliminate(budget + context, progress);
  PieceOutput out;
  out.kept_at_budget = elim.alive_count() - context;
  // A few removals more, logged: when other pieces cannot reach their budgets (their outline
  // needs more vertices), the merge takes these to keep the total exact.
  if (out.kept_at_budget == budget) {
    const std::size_t tail = std::min(budget > 3 ? budget - 3 : 0, budget / 50 + 8);
    elim.eliminate(budget + context - tail, progress, &out.tail);
  }
  auto global = [&](std::uint32_t cell) {
    const auto c = static_cast<std::uint32_t>(wc0) + cell % static_cast<std::uint32_t>(ww);
    const auto r = static_cast<std::uint32_t>(wr0) + cell / static_cast<std::uint32_t>(ww);
    return r * static_cast<std::uint32_t>(dem.width()) + c;
  };
  for (std::size_t id = 0; id < cells.size(); ++id) {
    if (!elim.alive(id) || !own_cell(cells[id])) continue;
    out.cells.push_back(global(cells[id]));
    out.z.push_back(grid.z[cells[id]]);
  }
  for (const core::OutlineEdge& e : elim.outline_edges()) {
    if (own_cell(e[0]) || own_cell(e[1])) out.outline.push_back({global(e[0]), global(e[1])});
  }
  for (core::Removal& r : out.tail) {
    out.tail_z.push_back(grid.z[r.cell]);
    r.cell = global(r.cell);
    r.prev = global(r.prev);
    r.next = global(r.next);
  }
  // The outputs of all pieces are held until the merge: no spare capacity.
  out.cells.shrink_to_fit();
  out.z.shrink_to_fit();
  out.outline.shrink_to_fit();
  out.tail.shrink_to_fit();
  out.tail_z.shrink_to_fit();
  report.simplify_s = seconds_since(t0);
  return out;
}

}  // namespace

std::size_t meta_memory_estimate(std::size_t kept_vertices, std::size_t pieces_bytes) {
  return kMetaBytesPerKeptVertex * kept_vertices + pieces_bytes;
}

double piece_value(const core::HeightGrid& window, int col0, int row0, const core::GridFrame& frame,
                   int points, int max_cells, std::uint64_t seed) {
  const int w = window.width, h = window.height;
  int s = 1;
  while (static_cast<double>((w + s - 1) / s) * ((h + s - 1) / s) > max_cells) ++s;
  core::HeightGrid sub;
  sub.width = (w + s - 1) / s;
  sub.height = (h + s - 1) / s;
  sub.z.resize(static_cast<std::size_t>(sub.width) * sub.height);
  for (int j = 0; j < sub.height; ++j) {
    for (int i = 0; i < sub.width; ++i)
      sub.z[sub.index(i, j)] = window.z[window.index(i * s, j * s)];
  }
  const core::Tin tin = core::grid_tin(sub, core::delaunay_diagonal(frame));
  if (tin.faces.empty() || points < 2) return 1.0;
  core::TriMesh mesh;
  const double m = frame.metres_per_unit;
  for (std::uint32_t cell : tin.cells) {
    const int i = static_cast<int>(cell % static_cast<std::uint32_t>(sub.width));
    const int j = static_cast<int>(cell / static_cast<std::uint32_t>(sub.width));
    const int c = col0 + i * s, r = row0 + j * s;
    mesh.xyz.insert(mesh.xyz.end(), {m * frame.u(c, r), m * frame.w(c, r), sub.z[cell]});
  }
  mesh.faces = tin.faces;
  core::fix_orientation(mesh);
  // note: the straightened geodesics' spacing on a DEM's grid TIN (dpts-eval's on T), not the
  // paper's 0.25 x the mean edge: the paths are pulled taut either way, and the values moved by
  // 3e-5 at most (San Gabriel's 16 pieces; the subsampling above moves them by 6e-3), at a
  // third of the time (San Gabriel, vp-meta: the values stage 1.48 -> 0.49 s on one thread).
  const core::SteinerGraph graph(mesh, kStraightenedDeltaFactorDem * core::mean_edge_length(mesh));
  const auto pts = core::sample_uniform(mesh, static_cast<std::size_t>(points), seed);
  const std::vector<double> gd = pairwise_distances(graph, pts);
  double sum = 0;
  std::size_t pairs = 0;
  const std::size_t k = pts.size();
  for (std::size_t a = 0; a < k; ++a) {
    for (std::size_t b = a + 1; b < k; ++b) {
      const double g = gd[a * k + b];
      if (!(g > 0) || !std::isfinite(g)) continue;
      const double dx = pts[a].x - pts[b].x, dy = pts[a].y - pts[b].y, dz = pts[a].z - pts[b].z;
      sum += std::min(1.0, std::sqrt(dx * dx + dy * dy + dz * dz) / g);
      ++pairs;
    }
  }
  return pairs ? sum / pairs : 1.0;
}

std::vector<core::Piece> divide_dem(const core::RasterSource& dem, const KeepTarget& keep,
                                    int levels, std::size_t tile_bytes, int halo,
                                    const core::Progress& progress, MetaStats& st,
                                    std::size_t max_vertices) {
  auto t0 = std::chrono::steady_clock::now();
  const core::BlockCounts bc = count_blocks(dem, std::max<std::size_t>(tile_bytes / 4, 1 << 20),
                                            progress, &st.valid_cells, &st.absurd_cells,
                                            &st.usual_nodata_cells);
  st.block = bc.block;
  st.count_s = seconds_since(t0);
  if (st.valid_cells == 0) {
    throw InputError(dem.no_valid_cell_message(st.absurd_cells));
  }
  core::DivisionOptions div;
  div.levels = levels;
  div.budget_bytes = tile_bytes;
  div.halo = halo;
  div.max_vertices = max_vertices;
  const core::GridFrame& f = dem.frame();
  div.col_metres = f.col_metres();
  div.row_metres = f.row_metres();
  std::vector<core::Piece> pieces = core::kd_divide(bc, div);
  // Each piece's outline count: the sum over its blocks (split lines fall on block lines).
  for (core::Piece& p : pieces) {
    const int bx1 = (p.col0 + p.width + bc.block - 1) / bc.block;
    const int by1 = (p.row0 + p.height + bc.block - 1) / bc.block;
    for (int by = p.row0 / bc.block; by < by1; ++by) {
      for (int bx = p.col0 / bc.block; bx < bx1; ++bx)
        p.outline += bc.outline[static_cast<std::size_t>(by) * bc.blocks_x + bx];
    }
  }
  std::size_t total = 0;
  for (const auto& p : pieces) total += p.vertices;
  if (total < 3) {
    throw InputError(dem.name() + ": " + kNothingToTriangulate);
  }
  st.input_vertices = total;
  st.target_vertices = target_count(keep, total);
  st.pieces.assign(pieces.size(), {});
  for (std::size_t i = 0; i < pieces.size(); ++i) st.pieces[i].piece = pieces[i];
  return pieces;
}

std::size_t pieces_in_flight(std::size_t pieces) { return std::min(pieces, worker_threads()); }

std::size_t pieces_in_flight_bytes(const std::vector<core::Piece>& pieces, int halo,
                                   std::size_t tile_bytes) {
  std::vector<std::size_t> bytes;
  bytes.reserve(pieces.size());
  for (const core::Piece& p : pieces)
    bytes.push_back(std::min(tile_bytes, core::piece_bytes(p, halo)));
  const std::size_t n = pieces_in_flight(pieces.size());
  std::partial_sort(bytes.begin(), bytes.begin() + static_cast<long>(n), bytes.end(),
                    std::greater<>());
  std::size_t sum = 0;
  for (std::size_t i = 0; i < n; ++i) sum += bytes[i];
  return sum;
}

void check_memory(const core::RasterSource& dem, std::size_t target, std::size_t need,
                  std::size_t limit) {
  if (limit == 0 || need <= limit) return;
  throw InputError(dem.name() + ": keeping " + std::to_string(target) +
                   " vertices, with its pieces in flight, needs about " +
                   format_bytes(static_cast<double>(need)) + ", more than the " +
                   format_bytes(static_cast<double>(limit)) +
                   " available; keep fewer (--keep, --vertices) or use a smaller --tile-mb");
}

namespace {

// Stage 2: the pieces' values, concurrently (each task reads its piece through its own handle);
// stage 3: their budgets, the paper's P2L per piece with the total exactly the target.
void value_and_budget(const core::RasterSource& dem, const std::vector<core::Piece>& pieces,
                      const MetaOptions& options, const core::Progress& progress, MetaStats& st) {
  SharedProgress shared(progress, pieces.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pieces.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        shared.check();
                        const core::Piece& p = pieces[i];
                        const core::HeightGrid g = dem.read(p.col0, p.row0, p.width, p.height);
                        tbb::this_task_arena::isolate([&] {
                          st.pieces[i].value =
                              piece_value(g, p.col0, p.row0, dem.frame(), options.value_points,
                                          options.value_cells, piece_seed(options.seed, i));
                        });
                        shared.update(i, 1.0, "values");
                      }
                    });
  shared.check();
  std::vector<std::size_t> counts;
  std::vector<double> values;
  for (const auto& p : st.pieces) {
    counts.push_back(p.piece.vertices);
    values.push_back(p.value);
  }
  const double p2l =
      100.0 * static_cast<double>(st.target_vertices) / static_cast<double>(st.input_vertices);
  const auto budgets = core::piece_budgets(counts, values, p2l);
  for (std::size_t i = 0; i < budgets.size(); ++i) st.pieces[i].budget = budgets[i];
}

// Stage 4: the pieces simplified concurrently; only their kept vertices and outline edges kept.
std::vector<PieceOutput> simplify_pieces(const core::RasterSource& dem,
                                         const std::vector<core::Piece>& pieces,
                                         const MetaOptions& options, const core::Progress& progress,
                                         MetaStats& st) {
  std::vector<PieceOutput> outputs(pieces.size());
  SharedProgress shared(progress, pieces.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pieces.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i < r.end(); ++i) {
                        shared.check();
                        const core::Progress piece_progress = [&](double fr, std::string_view) {
                          return shared.update(i, fr, "simplify");
                        };
                        outputs[i] = simplify_piece(dem, pieces[i], st.pieces[i].budget, options,
                                                    st.pieces[i], piece_progress);
                        release_free_memory();
                        shared.update(i, 1.0, "simplify");
                      }
                    });
  shared.check();
  return outputs;
}

// The merge's input: every piece's kept cells (sorted, with heights) and outline edges. Pieces
// whose outline kept them above budget leave a deficit; the others make it up from their
// logged tails, in proportion to their tails' lengths (largest remainder). Empties outputs.
void gather_kept(std::vector<PieceOutput>& outputs, MetaStats& st,
                 std::vector<std::pair<std::uint32_t, double>>& kept,
                 std::vector<core::OutlineEdge>& outline) {
  std::size_t deficit = 0, room = 0;
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    deficit += outputs[i].kept_at_budget - st.pieces[i].budget;
    room += outputs[i].tail.size();
  }
  std::vector<std::size_t> extra(outputs.size(), 0);
  if (deficit > 0 && room > 0) {
    std::vector<double> shares;
    std::vector<std::size_t> caps;
    for (const PieceOutput& o : outputs) {
      shares.push_back(static_cast<double>(std::min(deficit, room)) * o.tail.size() / room);
      caps.push_back(o.tail.size());
    }
    extra = core::largest_remainder(shares, std::min(deficit, room), caps);
  }
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    PieceOutput& o = outputs[i];
    // Take back the tail's removals after the first extra[i], last first, splitting chords.
    std::vector<core::OutlineEdge> edges = o.outline;
    std::sort(edges.begin(), edges.end());
    for (std::size_t j = o.tail.size(); j-- > extra[i];) {
      const core::Removal& r = o.tail[j];
      o.cells.push_back(r.cell);
      o.z.push_back(o.tail_z[j]);
      if (!r.outline) continue;
      const core::OutlineEdge chord{r.prev, r.next};
      const auto it = std::lower_bound(edges.begin(), edges.end(), chord);
      if (it == edges.end() || *it != chord) {
        throw std::logic_error("outline chord " + std::to_string(r.prev) + "-" +
                               std::to_string(r.next) + " missing when restoring cell " +
                               std::to_string(r.cell));
      }
      edges.erase(it);
      for (const core::OutlineEdge& e :
           {core::OutlineEdge{r.prev, r.cell}, core::OutlineEdge{r.cell, r.next}}) {
        edges.insert(std::lower_bound(edges.begin(), edges.end(), e), e);
      }
    }
    st.pieces[i].kept = o.cells.size();
    for (std::size_t k = 0; k < o.cells.size(); ++k) kept.emplace_back(o.cells[k], o.z[k]);
    outline.insert(outline.end(), edges.begin(), edges.end());
    o = {};
  }
  std::sort(kept.begin(), kept.end());
}

}  // namespace

MetaResult simplify_meta(const core::RasterSource& dem, const MetaOptions& options,
                         const core::Progress& progress, MetaStats* stats) {
  if (dem.cell_count() > core::kMaxGridCells) {
    throw InputError(dem.name() +
                     ": more than 2^32 cells, too many for the meta engine (32-bit cell ids)");
  }
  MetaStats local;
  MetaStats& st = stats ? *stats : local;
  const auto bytes = options.tile_bytes;

  // 1. Count surface vertices per block, streaming; divide.
  const std::vector<core::Piece> pieces =
      divide_dem(dem, options.keep, options.levels, bytes, options.halo, progress, st);
  check_memory(
      dem, st.target_vertices,
      meta_memory_estimate(st.target_vertices, pieces_in_flight_bytes(pieces, options.halo, bytes)),
      options.memory_limit_bytes);
  auto t0 = std::chrono::steady_clock::now();
  // 2, 3. Piece values and budgets.
  value_and_budget(dem, pieces, options, progress, st);
  st.values_s = seconds_since(t0);
  // 4. Simplify the pieces.
  t0 = std::chrono::steady_clock::now();
  std::vector<PieceOutput> outputs = simplify_pieces(dem, pieces, options, progress, st);
  st.simplify_s = seconds_since(t0);

  // 5. Merge: one Delaunay triangulation of all kept vertices, in a fixed order.
  st.peak_rss_before_merge_kb = peak_rss_kb();
  for (const auto& o : outputs) {
    st.kept_bytes += o.cells.capacity() * sizeof(std::uint32_t) + o.z.capacity() * sizeof(double) +
                     o.outline.capacity() * sizeof(core::OutlineEdge) +
                     o.tail.capacity() * sizeof(core::Removal) +
                     o.tail_z.capacity() * sizeof(double);
  }
  t0 = std::chrono::steady_clock::now();
  if (progress && !progress(0.0, "merge")) throw Cancelled();
  std::vector<std::pair<std::uint32_t, double>> kept;
  std::vector<core::OutlineEdge> outline;
  gather_kept(outputs, st, kept, outline);
  MetaResult result;
  std::vector<std::uint32_t> cells(kept.size());
  result.z.resize(kept.size());
  for (std::size_t k = 0; k < kept.size(); ++k)
    cells[k] = kept[k].first, result.z[k] = kept[k].second;
  kept = {};
  result.tin = core::merge_kept(dem.width(), dem.frame(), cells, outline);
  st.kept_vertices = result.tin.cells.size();
  st.merge_s = seconds_since(t0);
  if (progress && !progress(1.0, "merge")) throw Cancelled();
  return result;
}

}  // namespace dpts::par

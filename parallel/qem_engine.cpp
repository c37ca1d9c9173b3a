// The piece engine for qem (see qem_engine.hpp).
#include "parallel/qem_engine.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <functional>
#include <limits>
#include <list>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/errors.hpp"
#include "core/kd_division.hpp"
#include "core/mesh_check.hpp"
#include "core/qem.hpp"
#include "core/surface_sampling.hpp"
#include "parallel/memory.hpp"
#include "parallel/piece_support.hpp"

namespace dpts::par {
namespace {

// Where the mesh's vertices lie while it is simplified. A DEM in its own CRS: the frame, exact
// and linear (grid lines stay exactly straight). A reprojected DEM: its cells' true positions
// in the output CRS, scaled to frame units from cell (0, 0)'s: the frame is only a linear
// stand-in there, and a collapse's thin triangles, unfolded in the frame, came out folded in
// the output (295 faces on olympic_srtm1 to 10 %). Folds are tested where they matter.
struct Positions {
  const core::RasterSource* dem = nullptr;
  bool projected = false;
  double ox = 0, oy = 0, scale = 1;  // frame units = (output - o) * scale

  explicit Positions(const core::RasterSource& d) : dem(&d), projected(d.reprojected()) {
    if (!projected) return;
    const std::vector<double> o = d.output_xy_of_grid({0.0, 0.0});
    ox = o[0], oy = o[1];
    scale = d.metres_per_output_unit() / d.frame().metres_per_unit;
  }
  // x, y of cells (col, row pairs) in frame units; safe from concurrent tasks.
  std::vector<double> of(const std::vector<double>& grid_xy) const {
    if (!projected) return frame_of(grid_xy);
    std::vector<double> xy = dem->output_xy_of_grid(grid_xy);
    for (std::size_t i = 0; 2 * i < xy.size(); ++i) {
      xy[2 * i] = (xy[2 * i] - ox) * scale;
      xy[2 * i + 1] = (xy[2 * i + 1] - oy) * scale;
    }
    return xy;
  }
  // The frame's x, y of cells: the grid, linearly.
  std::vector<double> frame_of(const std::vector<double>& grid_xy) const {
    std::vector<double> xy(grid_xy.size());
    for (std::size_t i = 0; 2 * i < grid_xy.size(); ++i) {
      const int c = static_cast<int>(grid_xy[2 * i]), r = static_cast<int>(grid_xy[2 * i + 1]);
      xy[2 * i] = dem->frame().u(c, r);
      xy[2 * i + 1] = dem->frame().w(c, r);
    }
    return xy;
  }
  // With projected positions, folds are refused on the grid too (core's second plane, in
  // frame units): the map of a new position there, with a transformation of its own (one per
  // task).
  std::function<bool(const double*, double*)> to_plane() const {
    const auto grid_of = dem->grid_of_output_fn();
    const core::GridFrame f = dem->frame();
    return [grid_of, f, ox = ox, oy = oy, scale = scale](const double* xyz, double* xy) {
      double c, r;
      if (!grid_of(ox + xyz[0] / scale, oy + xyz[1] / scale, c, r)) return false;
      xy[0] = f.m[0][0] * c + f.m[0][1] * r;
      xy[1] = f.m[1][0] * c + f.m[1][1] * r;
      return true;
    };
  }
  // The mesh in the output CRS (heights in metres).
  void to_output(core::TriMesh& mesh) const {
    if (!projected) {
      dem->frame_mesh_to_output(mesh);
      return;
    }
    for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
      mesh.xyz[3 * v] = ox + mesh.xyz[3 * v] / scale;
      mesh.xyz[3 * v + 1] = oy + mesh.xyz[3 * v + 1] / scale;
      mesh.xyz[3 * v + 2] *= dem->frame().metres_per_unit;
    }
  }
  // With projected positions: the outline test of collinearity on the grid (cells given as
  // col, row of a window `width` wide), where the outline's runs are straight.
  template <typename Cell>
  std::function<bool(std::uint32_t, std::uint32_t, std::uint32_t)> collinear(
      const std::vector<Cell>* cells, std::uint64_t width) const {
    if (!projected) return nullptr;
    return [cells, width](std::uint32_t a, std::uint32_t v, std::uint32_t b) {
      auto at = [&](std::uint32_t i, long& c, long& r) {
        c = static_cast<long>((*cells)[i] % width);
        r = static_cast<long>((*cells)[i] / width);
      };
      long ca, ra, cv, rv, cb, rb;
      at(a, ca, ra), at(v, cv, rv), at(b, cb, rb);
      return (cv - ca) * (rb - ra) - (rv - ra) * (cb - ca) == 0;
    };
  }
};

// --max-error's test of a new triangle, in the frame (corners x, y on the grid's frame, z in
// frame units): every valid cell centre it covers (found from its box on the grid) lies
// within the bound of it. Cells come from `heights`: z(col, row) in metres, NaN for no-data,
// for cells in [c0, c1] x [r0, r1], the cells it can reach.
class VerticalBound {
 public:
  VerticalBound(const core::RasterSource& dem, double max_error_m) : frame_(dem.frame()) {
    frame_.inverse(to_grid_);
    unit_ = dem.frame().metres_per_unit;
    // note: a reprojected DEM's frame is a linear stand-in for the output CRS; heights
    // interpolated there differ slightly from those in the output CRS (3.000224 for a bound
    // of 3 on zion_canyon), so such a DEM gets 0.1 % of margin; any other 1e-9 for the
    // rounding of the transform back to the output CRS.
    limit_ = max_error_m / unit_ * (dem.reprojected() ? 0.999 : 1 - 1e-9);
  }

  template <class Heights>
  bool ok(const double* a, const double* b, const double* c, int c0, int r0, int c1, int r1,
          Heights&& z) const {
    const double* p[3] = {a, b, c};
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (const double* q : p) {
      for (int k = 0; k < 2; ++k) {
        const double g = to_grid_[k][0] * q[0] + to_grid_[k][1] * q[1];
        lo[k] = std::min(lo[k], g);
        hi[k] = std::max(hi[k], g);
      }
    }
    const double det = orient(a, b, c[0], c[1]);
    if (!(det > 0)) return true;  // the fold test refuses it
    const int col0 = std::max(c0, static_cast<int>(std::floor(lo[0])));
    const int col1 = std::min(c1, static_cast<int>(std::ceil(hi[0])));
    const int row0 = std::max(r0, static_cast<int>(std::floor(lo[1])));
    const int row1 = std::min(r1, static_cast<int>(std::ceil(hi[1])));
    constexpr double kOnEdge = -1e-12;  // barycentric slack: a cell on an edge counts
    for (int r = row0; r <= row1; ++r) {
      for (int col = col0; col <= col1; ++col) {
        const double u = frame_.u(col, r), w = frame_.w(col, r);
        const double l0 = orient(b, c, u, w) / det, l1 = orient(c, a, u, w) / det,
                     l2 = orient(a, b, u, w) / det;
        if (l0 < kOnEdge || l1 < kOnEdge || l2 < kOnEdge) continue;
        const double h = z(col, r);
        if (std::isnan(h)) continue;
        if (std::fabs(l0 * a[2] + l1 * b[2] + l2 * c[2] - h / unit_) > limit_) return false;
      }
    }
    return true;
  }

 private:
  static double orient(const double* s, const double* t, double u, double w) {
    return (t[0] - s[0]) * (w - s[1]) - (t[1] - s[1]) * (u - s[0]);
  }
  core::GridFrame frame_;
  double to_grid_[2][2];
  double unit_ = 1, limit_ = 0;
};

// Heights of any cell of the DEM for the merge's bound test: blocks of kSide x kSide cells read
// on demand, the least recently used dropped beyond `bytes`. Serial use only.
class BlockCache {
 public:
  BlockCache(const core::RasterSource& dem, std::size_t bytes)
      : dem_(dem), capacity_(std::max<std::size_t>(4, bytes / (sizeof(double) * kSide * kSide))) {}

  double operator()(int col, int row) {
    const int bc = col / kSide, br = row / kSide;
    const std::uint64_t key = static_cast<std::uint64_t>(br) << 32 | static_cast<std::uint32_t>(bc);
    if (last_ == nullptr || last_key_ != key) {
      auto it = blocks_.find(key);
      if (it == blocks_.end()) {
        if (blocks_.size() >= capacity_) {
          blocks_.erase(lru_.back());
          lru_.pop_back();
        }
        const int c0 = bc * kSide, r0 = br * kSide;
        Block b;
        b.grid = dem_.read(c0, r0, std::min(kSide, dem_.width() - c0),
                           std::min(kSide, dem_.height() - r0));
        lru_.push_front(key);
        b.at = lru_.begin();
        it = blocks_.emplace(key, std::move(b)).first;
      } else {
        lru_.splice(lru_.begin(), lru_, it->second.at);
      }
      last_ = &it->second.grid;
      last_key_ = key;
    }
    return last_->z[last_->index(col - bc * kSide, row - br * kSide)];
  }

 private:
  static constexpr int kSide = 256;
  struct Block {
    core::HeightGrid grid;
    std::list<std::uint64_t>::iterator at;
  };
  const core::RasterSource& dem_;
  std::size_t capacity_;
  std::unordered_map<std::uint64_t, Block> blocks_;
  std::list<std::uint64_t> lru_;  // most recent first
  const core::HeightGrid* last_ = nullptr;
  std::uint64_t last_key_ = 0;
};

// A collapse's output r as a piece's mesh in out: each vertex's DEM cell (cell_of, of its input
// vertex) and seam mark (seam, by input vertex).
template <typename CellOf>
void take_collapsed(core::QemResult&& r, const std::vector<char>& seam, CellOf&& cell_of,
                    QemPieceMesh& out) {
  out.mesh = std::move(r.mesh);
  out.quadrics = std::move(r.quadrics);
  out.plane_xy = std::move(r.plane_xy);
  out.cell.resize(r.source.size());
  out.seam.resize(r.source.size());
  for (std::size_t v = 0; v < r.source.size(); ++v) {
    out.cell[v] = cell_of(r.source[v]);
    out.seam[v] = seam[r.source[v]];
  }
}

// A piece's collapse (the pilot, qem_engine.hpp): collapsed unbounded to kPieceMost x its share
// of the target (its vertices less its seams', times the target's fraction, and its seams),
// then on while a collapse costs at most the pilot's bound, down to its share at the least:
// the pieces never keep fewer than the target together, which the merge could not undo (a
// floor of a quarter share kept 8,008 of 9,000 vertices asked of an island in a flat sea).
// note: a piece keeps what the surface needs there (kilauea_utm5's sea, all outline round its
// salt-and-pepper voids: up to 5 x its share, forced), where a count by size made a piece
// whose voids' outlines filled its count collapse all else it could, at any cost: kilauea's
// coastal cliffs came out 171 m off (vertical RMSE 5.36 m; 0.60 m so).
// The pilot follows its pieces on down to kPieceLeast x their shares: where the merge of the
// whole DEM would take them, about.
constexpr double kPieceMost = 8.0, kPieceLeast = 0.25;
// The pilot keeps a copy of its piece's collapse at kPieceResume x its share, and once it
// knows the bound goes on from there to the piece's output, where every collapse the copy
// made cost at most the bound: the collapses a piece makes from scratch, as a bounded run
// makes those of an unbounded one until one costs more than its bound (Collapser::run).
// note: so a pilot piece is not simplified twice: San Gabriel to 10 %, 8 of its 64 pieces,
// about a tenth of its CPU. A copy holds about what its piece's collapse held at first (its
// arrays are the whole piece's; core::piece_bytes): at most kPilotCopies, while they fit one
// tile together, held until the pilot's end (kilauea_utm5 at --tile-mb 4: 8 copies of
// 10k-vertex pieces took its peak from 71 to 102 MB; 1 fits its tile).
constexpr double kPieceResume = 2.0;
constexpr std::size_t kPilotCopies = 8;
// The merge never makes a collapse costing this x what the pilot finds the merge of the whole
// DEM would stop at (QemSweep::add): kilauea_utm5's catastrophes cost 1e6 x that, its merges'
// last collapses 1 to 20 x.
constexpr double kMergeCostCap = 1000.0;
constexpr double kAnyCost = std::numeric_limits<double>::infinity();

// A piece's window read and made into a mesh ready to collapse, beside what its collapse's
// tests read (its cells, seams, outline test and vertical bound), which they point at: it is
// neither copied nor moved.
class PieceCollapse {
 public:
  PieceCollapse(const core::RasterSource& dem, const Positions& positions, const core::Piece& p,
                double fraction, const QemEngineOptions& options, PieceReport& report,
                core::Progress progress)
      : dem_(dem),
        wc0_(p.col0),
        wr0_(p.row0),
        // The piece's cells and one more column and row (the next pieces' first): the grid
        // squares whose top-left corner is the piece's.
        wc1_(std::min(dem.width(), p.col0 + p.width + 1)),
        wr1_(std::min(dem.height(), p.row0 + p.height + 1)),
        ww_(wc1_ - wc0_),
        fraction_(fraction) {
    const int wh = wr1_ - wr0_;
    grid_ = read_window(dem, wc0_, wr0_, ww_, wh, report.read_s);
    t0_ = std::chrono::steady_clock::now();
    std::vector<std::uint32_t> opposites;
    core::Tin tin = core::grid_tin(grid_, core::delaunay_diagonal(dem.frame()), &opposites);
    if (tin.faces.empty()) return;
    cells_ = std::move(tin.cells);
    const double unit = dem.frame().metres_per_unit;
    core::TriMesh mesh;
    std::vector<double> grid_xy(2 * cells_.size());
    for (std::size_t v = 0; v < cells_.size(); ++v) {
      grid_xy[2 * v] = wc0_ + static_cast<int>(cells_[v] % static_cast<std::uint32_t>(ww_));
      grid_xy[2 * v + 1] = wr0_ + static_cast<int>(cells_[v] / static_cast<std::uint32_t>(ww_));
    }
    const std::vector<double> xy = positions.of(grid_xy);
    core::QemOptions qo;
    if (positions.projected) {
      qo.plane_xy = positions.frame_of(grid_xy);
      qo.to_plane = positions.to_plane();
    }
    grid_xy = {};
    mesh.xyz.resize(3 * cells_.size());
    seam_.assign(cells_.size(), 0);
    for (std::size_t v = 0; v < cells_.size(); ++v) {
      const int c = static_cast<int>(cells_[v] % static_cast<std::uint32_t>(ww_));
      const int r = static_cast<int>(cells_[v] / static_cast<std::uint32_t>(ww_));
      mesh.xyz[3 * v] = xy[2 * v];
      mesh.xyz[3 * v + 1] = xy[2 * v + 1];
      mesh.xyz[3 * v + 2] = grid_.z[cells_[v]] / unit;
      // A window side inside the raster is a seam: another window has its cells too.
      const bool seam = (c == 0 && wc0_ > 0) || (c == ww_ - 1 && wc1_ < dem.width()) ||
                        (r == 0 && wr0_ > 0) || (r == wh - 1 && wr1_ < dem.height());
      seam_[v] = seam ? 1 : 0;
      locked_ += seam ? 1 : 0;
    }
    qo.locked = seam_;
    mesh.faces = std::move(tin.faces);
    core::fix_orientation(mesh, &opposites);
    qo.opposites = std::move(opposites);
    qo.outline_collinear = positions.collinear(&cells_, static_cast<std::uint64_t>(ww_));
    chord_ = dem.outline_chord_test(wc0_, wr0_, ww_);
    if (chord_) {
      qo.outline_chord_ok = [this](std::uint32_t a, std::uint32_t b) {
        return chord_(cells_[a], cells_[b]);
      };
    }
    keep_ = share(options.slack);
    if (options.max_error > 0) {
      // The window holds every cell the piece's triangles cover.
      bound_.emplace(dem, options.max_error);
      qo.triangle_ok = [this](const double* a, const double* b, const double* c) {
        return bound_->ok(a, b, c, wc0_, wr0_, wc1_ - 1, wr1_ - 1, [this](int col, int row) {
          return grid_.z[grid_.index(col - wc0_, row - wr0_)];
        });
      };
    } else {
      grid_ = {};
    }
    collapse_.emplace(std::move(mesh), std::move(qo), std::move(progress));
  }
  PieceCollapse(const PieceCollapse&) = delete;
  PieceCollapse& operator=(const PieceCollapse&) = delete;

  // No faces: nothing to collapse (an empty output).
  bool empty() const { return !collapse_; }
  // s x the piece's share of the target, and its seams.
  std::size_t share(double s) const {
    const std::size_t n = cells_.size();
    return std::min<std::size_t>(
        n, locked_ + static_cast<std::size_t>(
                         std::ceil(s * fraction_ * static_cast<double>(n - locked_))));
  }
  // Its count by size: slack x its share.
  std::size_t keep() const { return keep_; }
  std::size_t vertices() const { return cells_.size(); }
  // Its collapse, once (not empty()).
  core::QemCollapse take_collapse() {
    core::QemCollapse c = std::move(*collapse_);
    collapse_.reset();
    return c;
  }

  // The piece's output from c (its collapse or a copy of it), its counts and time in report.
  QemPieceMesh finish(core::QemCollapse&& c, PieceReport& report,
                      const core::Progress& progress) {
    core::QemResult r = c.result();
    if (progress && !progress(1.0, "simplify")) throw Cancelled();
    grid_ = {};
    QemPieceMesh out;
    take_collapsed(
        std::move(r), seam_,
        [&](std::uint32_t input) {
          // note: 64-bit: a raster may have more than 2^32 cells (a window has fewer).
          const std::uint32_t local = cells_[input];
          const std::uint64_t col =
              static_cast<std::uint64_t>(wc0_) + local % static_cast<std::uint32_t>(ww_);
          const std::uint64_t row =
              static_cast<std::uint64_t>(wr0_) + local / static_cast<std::uint32_t>(ww_);
          return row * static_cast<std::uint64_t>(dem_.width()) + col;
        },
        out);
    out.mesh.xyz.shrink_to_fit();
    out.mesh.faces.shrink_to_fit();
    out.quadrics.shrink_to_fit();
    out.plane_xy.shrink_to_fit();
    report.budget = keep_;
    report.kept = out.cell.size();
    report.simplify_s = seconds_since(t0_);
    return out;
  }

 private:
  const core::RasterSource& dem_;
  const int wc0_, wr0_, wc1_, wr1_, ww_;
  const double fraction_;
  core::HeightGrid grid_;
  std::chrono::steady_clock::time_point t0_;
  std::vector<std::uint32_t> cells_;  // per vertex, its cell in the window (row-major)
  std::vector<char> seam_;            // per vertex, on a seam (locked)
  std::size_t locked_ = 0, keep_ = 0;
  std::function<bool(std::uint64_t, std::uint64_t)> chord_;
  std::optional<VerticalBound> bound_;
  std::optional<core::QemCollapse> collapse_;
};

// A pilot piece's collapse from kPieceMost x its share down to kPieceLeast x, in steps: the
// vertices left after each, the most any collapse after the first step cost by then, and its
// counts at kPieceMost x, kPieceLeast x, 1 x and slack x its share; maybe a copy of it at
// kPieceResume x its share, and the most a collapse past kPieceMost had cost then.
struct PilotCurve {
  std::vector<std::size_t> left;
  std::vector<double> cost;
  std::size_t most = 0, least = 0, keep = 0, share = 0, vertices = 0;
  std::unique_ptr<PieceCollapse> piece;  // with resume
  std::optional<core::QemCollapse> resume;
  double resume_cost = 0;
  // The fewest vertices it came to (at the pilot's end).
  std::size_t fewest() const { return left.empty() ? most : left.back(); }
  // What the piece keeps with collapses past `most` bounded by `bound`, at least `floor`.
  std::size_t kept_at(double bound, std::size_t floor) const {
    std::size_t k = most;
    for (std::size_t i = 0; i < left.size() && cost[i] <= bound; ++i) k = left[i];
    return std::max(k, floor);
  }
};

// A piece's collapse to its output: bounded by cost_bound (>= 0: the pilot's), else to its
// count by size.
QemPieceMesh simplify_piece(const core::RasterSource& dem, const Positions& positions,
                            const core::Piece& p, double fraction, double cost_bound,
                            const QemEngineOptions& options, PieceReport& report,
                            const core::Progress& progress) {
  PieceCollapse piece(dem, positions, p, fraction, options, report, progress);
  if (piece.empty()) return {};
  core::QemCollapse c = piece.take_collapse();
  if (cost_bound >= 0) {
    c.collapse(piece.share(kPieceMost), kAnyCost);
    c.collapse(piece.share(1.0), cost_bound);
  } else {
    c.collapse(piece.keep(), kAnyCost);
  }
  return piece.finish(std::move(c), report, progress);
}

// A pilot piece's collapse into curve (and the piece, with a copy of its collapse, where
// `copy`).
void pilot_piece(const core::RasterSource& dem, const Positions& positions, const core::Piece& p,
                 double fraction, const QemEngineOptions& options, PieceReport& report,
                 const core::Progress& progress, bool copy, PilotCurve& curve) {
  auto piece = std::make_unique<PieceCollapse>(dem, positions, p, fraction, options, report,
                                               progress);
  if (piece->empty()) return;
  // note: freed at the end, where a copy goes on (the piece's tests are held for it).
  core::QemCollapse c = piece->take_collapse();
  curve.most = piece->share(kPieceMost);
  curve.least = piece->share(kPieceLeast);
  curve.keep = piece->keep();
  curve.share = piece->share(1.0);
  curve.vertices = piece->vertices();
  // note: never past the least a piece collapses to (its share, or its count by size).
  const std::size_t resume = std::max(piece->share(kPieceResume), curve.keep);
  c.collapse(curve.most, kAnyCost);
  double most = 0;
  for (std::size_t left = curve.most;;) {
    if (copy && !curve.resume && c.vertices() <= resume && c.vertices() >= curve.keep) {
      curve.resume.emplace(c);
      curve.resume_cost = most;
    }
    if (left <= curve.least) break;
    left = std::max(curve.least, left - std::max<std::size_t>(1, left / 20));
    c.collapse(left, kAnyCost);
    most = std::max(most, c.max_cost_made());
    curve.left.push_back(c.vertices());
    curve.cost.push_back(most);
  }
  if (curve.resume) curve.piece = std::move(piece);
}

// What stitching outputs [first, end) appends at most: their vertices (seam vertices counted
// in each) and faces.
struct StitchedSize {
  std::size_t vertices = 0, faces = 0;
};
StitchedSize stitched_size(const std::vector<QemPieceMesh>& outputs, std::size_t first,
                           std::size_t end) {
  StitchedSize n;
  for (std::size_t i = first; i < end; ++i) {
    n.vertices += outputs[i].cell.size();
    n.faces += outputs[i].mesh.faces.size();
  }
  return n;
}

// Piece output o's vertices appended after `vertices` others, each seam vertex (by cell, in
// seam_vertex) once, and its faces to `faces`: fresh(v) for each vertex of o that is new,
// repeat(v, id) for a seam vertex already there as id (whose quadric takes o's).
template <typename Fresh, typename Repeat>
void append_stitched(const QemPieceMesh& o,
                     std::unordered_map<std::uint64_t, std::uint32_t>& seam_vertex,
                     std::size_t vertices, std::vector<std::array<std::uint32_t, 3>>& faces,
                     Fresh&& fresh, Repeat&& repeat) {
  std::vector<std::uint32_t> id(o.cell.size());
  auto next = static_cast<std::uint32_t>(vertices);
  for (std::size_t v = 0; v < o.cell.size(); ++v) {
    if (o.seam[v]) {
      const auto [it, added] = seam_vertex.emplace(o.cell[v], next);
      id[v] = it->second;
      if (!added) {
        repeat(v, it->second);
        continue;
      }
    } else {
      id[v] = next;
    }
    fresh(v);
    ++next;
  }
  for (const auto& t : o.mesh.faces) faces.push_back({id[t[0]], id[t[1]], id[t[2]]});
}

double qem_fraction(const MetaStats& st) {
  return static_cast<double>(st.target_vertices) / static_cast<double>(st.input_vertices);
}

// Whether a raster cell lies in the window of a piece at or after a given index (k-d order).
// A window is its piece's cells and one more column and row, so a cell lies in the windows of
// the pieces that own it and its neighbours to the left, above and above left; pieces are
// unions of blocks, so a map from blocks to pieces finds those.
class LaterWindows {
 public:
  LaterWindows(const std::vector<core::Piece>& pieces, int block, int width, int height)
      : block_(static_cast<std::uint64_t>(std::max(1, block))),
        bx_((static_cast<std::uint64_t>(width) + block_ - 1) / block_),
        width_(static_cast<std::uint64_t>(width)) {
    const std::uint64_t by = (static_cast<std::uint64_t>(height) + block_ - 1) / block_;
    owner_.assign(bx_ * by, -1);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const core::Piece& p = pieces[i];
      const std::uint64_t c0 = static_cast<std::uint64_t>(p.col0),
                          r0 = static_cast<std::uint64_t>(p.row0);
      for (std::uint64_t r = r0 / block_; r * block_ < r0 + static_cast<std::uint64_t>(p.height);
           ++r) {
        for (std::uint64_t c = c0 / block_; c * block_ < c0 + static_cast<std::uint64_t>(p.width);
             ++c) {
          owner_[r * bx_ + c] = static_cast<std::int64_t>(i);
        }
      }
    }
  }
  // Whether the cell lies in the window of a piece outside [from, end).
  bool outside(std::uint64_t cell, std::size_t from, std::size_t end) const {
    const std::uint64_t c = cell % width_, r = cell / width_;
    for (std::uint64_t dr = 0; dr < 2; ++dr) {
      for (std::uint64_t dc = 0; dc < 2; ++dc) {
        if (dc > c || dr > r) continue;
        const std::int64_t o = owner(c - dc, r - dr);
        if (o >= 0 && (static_cast<std::size_t>(o) < from || static_cast<std::size_t>(o) >= end))
          return true;
      }
    }
    return false;
  }
  bool later(std::uint64_t cell, std::size_t from) const { return outside(cell, 0, from); }
  // Whether the cell belongs to a piece at or after `from`.
  bool owned_later(std::uint64_t cell, std::size_t from) const {
    const std::int64_t o = owner(cell % width_, cell / width_);
    return o >= 0 && static_cast<std::size_t>(o) >= from;
  }

 private:
  // The piece owning the cell at column c, row r (-1: none).
  std::int64_t owner(std::uint64_t c, std::uint64_t r) const {
    return owner_[(r / block_) * bx_ + c / block_];
  }

  std::uint64_t block_;
  std::uint64_t bx_;
  std::uint64_t width_;
  std::vector<std::int64_t> owner_;
};

// The merge, a group of pieces at a time (qem_engine.hpp). What is open: the mesh of the
// pieces merged so far that a later group can still change, in frame units, with per vertex
// its quadric, raster cell, whether it lay on a window side, its x, y on the grid (reprojected
// DEMs), and its id in the output once it is final.
class QemSweep {
 public:
  QemSweep(const core::RasterSource& dem, const QemEngineOptions& options,
           const std::vector<core::Piece>& pieces, MetaStats& st)
      : dem_(dem),
        options_(options),
        positions_(dem),
        later_(pieces, st.block, dem.width(), dem.height()),
        st_(st) {
    // Each piece's weight in the target's shares: its surface vertices, or with the pilot's
    // bound the vertices it kept (estimated from the pilot's until it is merged, by its
    // vertices beside voids and the rest).
    weight_.resize(pieces.size());
    outline_.resize(pieces.size());
    forced_per_outline_ = st.piece_cost_bound >= 0 ? st.pilot_forced_per_outline : 0.0;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      outline_[i] = static_cast<double>(std::min(pieces[i].outline, pieces[i].vertices));
      const double v = static_cast<double>(pieces[i].vertices), o = outline_[i];
      weight_[i] = st.piece_cost_bound >= 0
                       ? (v - o) * st.pilot_kept_per_inner + o * st.pilot_kept_per_outline
                       : v;
    }
    if (options.max_error > 0) {
      bound_.emplace(dem, options.max_error);
      cells_.emplace(dem, options.tile_bytes);
    }
  }

  // Pieces [first, end) (their outputs emptied) stitched to what is open at their seams,
  // collapsed together with it, and what no later piece can change written to the output (all
  // of it when no piece follows).
  void add(std::vector<QemPieceMesh>& outputs, const std::vector<core::Piece>& pieces,
           std::size_t first, std::size_t end, const core::Progress& progress) {
    // note: the weights of the pieces merged so far are theirs, the later ones' estimates, here
    // and under dpts-mpi alike (where every piece is in before the first group's merge).
    if (st_.piece_cost_bound >= 0) {
      for (std::size_t i = first; i < end; ++i)
        weight_[i] = static_cast<double>(outputs[i].cell.size());
    }
    done_ = 0;
    total_ = 0;
    for (std::size_t i = 0; i < weight_.size(); ++i) (i < end ? done_ : total_) += weight_[i];
    total_ += done_;
    // Of the weights, the vertices no collapse removes (the outlines round voids), estimated.
    double forced_done = 0, forced_total = 0;
    for (std::size_t i = 0; i < weight_.size(); ++i) {
      const double f = std::min(weight_[i], forced_per_outline_ * outline_[i]);
      (i < end ? forced_done : forced_total) += f;
    }
    forced_total += forced_done;
    const bool last = end == pieces.size();
    if (first == 0 && last && !bound_) {
      const auto t0 = std::chrono::steady_clock::now();
      // note: the runs' freed memory is not handed back (release_free_memory): the merge
      // takes it up again (San Gabriel to 10 %, 2 threads, with the trim after the pieces
      // gone too: 29-32k -> 23-25k pages faulted in, peak 105 -> 119-123 MB).
      premerge(outputs, pieces);
      st_.premerge_s = seconds_since(t0);
    }
    stitch(outputs, first, end);
    // Locked: final vertices, and those a later piece's window shares (the open boundary).
    std::vector<char> locked(cell_.size(), 0);
    // The open boundary: cells of these pieces (or earlier ones) and cells of later pieces
    // that these pieces' windows hold (their last column and row).
    std::size_t boundary = 0, borrowed = 0, held = 0;  // and final vertices still open
    for (std::size_t v = 0; v < cell_.size(); ++v) {
      const bool final_vertex = out_id_[v] != kNone;
      const bool open = !final_vertex && seam_[v] && later_.later(cell_[v], end);
      locked[v] = final_vertex || open;
      const bool later_cell = open && later_.owned_later(cell_[v], end);
      boundary += open && !later_cell ? 1 : 0;
      borrowed += later_cell ? 1 : 0;
      held += final_vertex ? 1 : 0;
    }
    // The count to reach: the target's share of the pieces merged so far, plus the part of
    // their open boundary (full resolution, locked) that later groups will remove, plus the
    // later pieces' cells held here: those are in the later pieces' share (counted in their
    // vertices), not in these pieces'. (Counted in this share, they once made a DEM of two
    // groups at --keep 100 % lose as many vertices: kilauea_utm5 657,336 -> 656,339.)
    const double fraction = qem_fraction(st_);
    // note: the target less the forced vertices is shared by the rest of the weights: a group
    // whose voids' outlines hold more than its share of the whole cannot reach it (kilauea_utm5
    // at --tile-mb 4, its last group the sea: 70,115 vertices kept of 65,734).
    const double target = static_cast<double>(st_.target_vertices);
    const double free_share = total_ > forced_total
                                  ? (done_ - forced_done) / (total_ - forced_total)
                                  : done_ / total_;
    const std::size_t want =
        last ? st_.target_vertices
             : static_cast<std::size_t>(
                   std::llround(forced_done + std::max(0.0, target - forced_total) * free_share +
                                (1 - std::min(1.0, fraction)) * static_cast<double>(boundary))) +
                   borrowed;
    const std::size_t dropped = written_ - held;
    const std::size_t keep = want > dropped ? want - dropped : 0;
    // The pilot's cap (run_pilot): a collapse no merge of all the pieces in one group would
    // make, which a count the outline and the voids leave out of reach of the groups' shares
    // asked for: kilauea_utm5 at --tile-mb 4 (16 groups), the last group's coastal cliffs
    // 124 m off, vertical RMSE 7.7 m; 19 m and 0.99 m so, 70,115 vertices kept for 65,734.
    const double bound = st_.merge_cost_cap > 0 ? st_.merge_cost_cap
                                                : std::numeric_limits<double>::infinity();
    core::QemResult r = collapse(std::move(locked), keep, bound, progress);
    // Per vertex data through the collapse.
    std::vector<std::uint64_t> cell(r.source.size());
    std::vector<char> seam(r.source.size());
    std::vector<std::uint32_t> out_id(r.source.size());
    std::vector<double> out_xyz(3 * r.source.size());
    for (std::size_t v = 0; v < r.source.size(); ++v) {
      cell[v] = cell_[r.source[v]];
      seam[v] = seam_[r.source[v]];
      out_id[v] = out_id_[r.source[v]];
      std::copy_n(out_xyz_.begin() + 3 * r.source[v], 3, out_xyz.begin() + 3 * v);
    }
    cell_ = std::move(cell);
    seam_ = std::move(seam);
    out_id_ = std::move(out_id);
    out_xyz_ = std::move(out_xyz);
    mesh_ = std::move(r.mesh);
    quadrics_ = std::move(r.quadrics);
    plane_xy_ = std::move(r.plane_xy);
    write_final(last ? std::vector<char>(cell_.size(), 1) : finals(end));
  }

  // The output: every vertex and face written (in the output CRS); empty when they went to
  // options.sink.
  core::TriMesh finish() { return std::move(out_); }
  std::size_t vertices_written() const { return written_; }

 private:
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;
  // note: how far from the open boundary (in edges of the merged mesh) vertices stay open: a
  // later group's collapses can reach that far back into this one's, so that its seam is
  // simplified with the vertices around it, not against a wall.
  static constexpr int kOpenRings = 8;

  // The pieces' outputs appended to what is open, seam vertices (by cell) once, their
  // quadrics summed: every vertex's quadric is then what one whole-DEM run would have given.
  void stitch(std::vector<QemPieceMesh>& outputs, std::size_t first, std::size_t end) {
    std::unordered_map<std::uint64_t, std::uint32_t> seam_vertex;
    for (std::size_t v = 0; v < cell_.size(); ++v) {
      if (seam_[v] && out_id_[v] == kNone)
        seam_vertex.emplace(cell_[v], static_cast<std::uint32_t>(v));
    }
    {
      // Sized once: growing by doubling would briefly hold twice the merge's largest arrays.
      const StitchedSize added = stitched_size(outputs, first, end);
      const std::size_t vertices = cell_.size() + added.vertices;
      const std::size_t faces = mesh_.faces.size() + added.faces;
      mesh_.xyz.reserve(3 * vertices);
      mesh_.faces.reserve(faces);
      quadrics_.reserve(vertices);
      if (positions_.projected) plane_xy_.reserve(2 * vertices);
      cell_.reserve(vertices);
      seam_.reserve(vertices);
      out_id_.reserve(vertices);
      out_xyz_.reserve(3 * vertices);
    }
    for (std::size_t i = first; i < end; ++i) {
      QemPieceMesh& o = outputs[i];
      append_stitched(
          o, seam_vertex, cell_.size(), mesh_.faces,
          [&](std::size_t v) {
            cell_.push_back(o.cell[v]);
            seam_.push_back(o.seam[v]);
            out_id_.push_back(kNone);
            out_xyz_.insert(out_xyz_.end(), 3, 0.0);
            mesh_.xyz.insert(mesh_.xyz.end(), o.mesh.xyz.begin() + 3 * v,
                             o.mesh.xyz.begin() + 3 * v + 3);
            quadrics_.push_back(o.quadrics[v]);
            if (positions_.projected) {
              plane_xy_.insert(plane_xy_.end(), o.plane_xy.begin() + 2 * v,
                               o.plane_xy.begin() + 2 * v + 2);
            }
          },
          [&](std::size_t v, std::uint32_t at) { quadrics_[at] += o.quadrics[v]; });
      o = {};
    }
  }

  // The collapse's rules for a mesh whose vertices lie at `cells` (which must outlive it):
  // the outline's tests and, on a reprojected DEM, the grid's plane.
  void rules(core::QemOptions& qo, const std::vector<std::uint64_t>* cells) const {
    if (positions_.projected) qo.to_plane = positions_.to_plane();
    qo.outline_collinear = positions_.collinear(cells, static_cast<std::uint64_t>(dem_.width()));
    if (chord_) {
      qo.outline_chord_ok = [this, cells](std::uint32_t a, std::uint32_t b) {
        return chord_((*cells)[a], (*cells)[b]);
      };
    }
  }

  // A run of the pre-merge: its pieces stitched at their own seams, being collapsed.
  struct Run {
    QemPieceMesh mesh;  // stitched (cells and seams); the collapse's output
    std::optional<core::QemCollapse> collapse;
    std::size_t keep = 0;
    std::size_t frozen = 0;  // its vertices shared with other runs
  };

  // Pieces [from, end) (their outputs emptied) stitched into run u, its collapse prepared.
  void build_run(Run& u, std::vector<QemPieceMesh>& outputs, std::size_t from,
                 std::size_t end) const {
    QemPieceMesh m;
    std::unordered_map<std::uint64_t, std::uint32_t> seam_vertex;
    // Sized once (as in stitch): growing by doubling copied and faulted in each array twice.
    const StitchedSize size = stitched_size(outputs, from, end);
    m.mesh.xyz.reserve(3 * size.vertices);
    m.mesh.faces.reserve(size.faces);
    m.quadrics.reserve(size.vertices);
    if (positions_.projected) m.plane_xy.reserve(2 * size.vertices);
    m.cell.reserve(size.vertices);
    m.seam.reserve(size.vertices);
    double vertices = 0;
    for (std::size_t i = from; i < end; ++i) {
      vertices += weight_[i];
      QemPieceMesh& o = outputs[i];
      append_stitched(
          o, seam_vertex, m.cell.size(), m.mesh.faces,
          [&](std::size_t v) {
            m.cell.push_back(o.cell[v]);
            m.seam.push_back(o.seam[v]);
            m.mesh.xyz.insert(m.mesh.xyz.end(), o.mesh.xyz.begin() + 3 * v,
                              o.mesh.xyz.begin() + 3 * v + 3);
            m.quadrics.push_back(o.quadrics[v]);
            if (positions_.projected) {
              m.plane_xy.insert(m.plane_xy.end(), o.plane_xy.begin() + 2 * v,
                                o.plane_xy.begin() + 2 * v + 2);
            }
          },
          [&](std::size_t v, std::uint32_t at) { m.quadrics[at] += o.quadrics[v]; });
      o = {};
    }
    core::QemOptions qo;
    qo.frozen.assign(m.cell.size(), 0);
    for (std::size_t v = 0; v < m.cell.size(); ++v) {
      qo.frozen[v] = m.seam[v] && later_.outside(m.cell[v], from, end);
      u.frozen += qo.frozen[v] ? 1 : 0;
    }
    // The run's share of the target, at least: the merge goes on from there.
    u.keep = static_cast<std::size_t>(
        std::ceil(static_cast<double>(st_.target_vertices) * vertices / total_));
    u.mesh.cell = std::move(m.cell);
    u.mesh.seam = std::move(m.seam);
    rules(qo, &u.mesh.cell);
    qo.quadrics = std::move(m.quadrics);
    qo.plane_xy = std::move(m.plane_xy);
    u.collapse.emplace(std::move(m.mesh), std::move(qo));
  }

  // The pre-merge (a whole DEM merged as one group), the serial merge's collapses that need
  // not wait for it: runs of kRunPieces consecutive pieces (in k-d order, so mostly
  // neighbours), each stitched at its own seams and collapsed on its own, concurrently, below
  // one cost bound (at most), with the seams it shares with pieces outside the run frozen
  // (their quadrics are partial there). The bound: the K-th least cost queued over all runs,
  // K the collapses left to the target less the frozen vertices. Costs rise as collapses go on
  // (quadrics add up), so the merge's last collapse costs more, and a collapse inside a run
  // below the bound is one the merge would have made too, in the same order among the run's
  // own. kPremergeRounds rounds, each bound from the queues the round before left: San Gabriel
  // to 10 %, 0.72 then 1.16, where the merge's last collapse costs 2.04 (15.1k of its 34.3k
  // collapses moved). The rest is left to the merge.
  // note: the runs' builds and first costs are work the merge then does again: at 2 threads
  // San Gabriel's merge stage stays about as long (0.16-0.19 s against 0.17-0.20); it pays
  // where the merge has much to do (olympic_srtm1 to 2 %: 1.51 -> 1.07 s, the flat sea's
  // collapses in parallel) and with more threads.
  static constexpr std::size_t kRunPieces = 4;
  static constexpr int kPremergeRounds = 2;

  void premerge(std::vector<QemPieceMesh>& outputs, const std::vector<core::Piece>& pieces) {
    const std::size_t n = pieces.size(), runs = (n + kRunPieces - 1) / kRunPieces;
    std::size_t vertices = 0;
    for (std::size_t i = 0; i < n; ++i) vertices += outputs[i].cell.size();
    if (runs < 2 || vertices < options_.premerge_vertices) return;
    std::vector<Run> run(runs);
    tbb::parallel_for(std::size_t{0}, runs, [&](std::size_t r) {
      build_run(run[r], outputs, r * kRunPieces, std::min(n, (r + 1) * kRunPieces));
    });
    for (int round = 0; round < kPremergeRounds; ++round) {
      std::vector<float> costs;
      std::size_t alive = 0, frozen = 0;
      for (const Run& u : run) {
        u.collapse->queued_costs(costs);
        alive += u.collapse->vertices();
        frozen += u.frozen;
      }
      // note: the frozen vertices' collapses are queued nowhere yet, and may be the merge's
      // cheapest (seams across a flat sea cost nothing): each is counted as one the merge
      // makes for free, so K leaves them out. Without, olympic_srtm1 to 2 % bounded its
      // second round at 166 where the merge's last collapse cost 0; no bound (K past the
      // queue) would let each run collapse down to its share (round 7's loss).
      if (alive <= st_.target_vertices + frozen) break;
      const std::size_t k = alive - st_.target_vertices - frozen;
      if (k > costs.size()) break;
      std::nth_element(costs.begin(), costs.begin() + static_cast<std::ptrdiff_t>(k - 1),
                       costs.end());
      const double bound = costs[k - 1];
      costs = {};
      std::atomic<std::size_t> made{0};
      tbb::parallel_for(std::size_t{0}, runs, [&](std::size_t r) {
        made += run[r].collapse->collapse(run[r].keep, bound);
      });
      st_.premerge_collapses += made;
    }
    tbb::parallel_for(std::size_t{0}, runs, [&](std::size_t r) {
      Run& u = run[r];
      core::QemResult res = u.collapse->result();
      u.collapse.reset();
      take_collapsed(
          std::move(res), u.mesh.seam, [&](std::uint32_t input) { return u.mesh.cell[input]; },
          outputs[r * kRunPieces]);
      u = {};
    });
  }

  // What is open collapsed to `keep` vertices, the locked ones (if any) never moving.
  // note: whether any is locked is read off `locked` itself, not passed beside it: a count
  // kept apart once missed the later pieces' cells and left every seam between groups open.
  core::QemResult collapse(std::vector<char> locked, std::size_t keep, double max_cost,
                           const core::Progress& progress) {
    core::QemOptions qo;
    if (std::find(locked.begin(), locked.end(), 1) != locked.end()) qo.locked = std::move(locked);
    qo.quadrics = std::move(quadrics_);
    qo.plane_xy = std::move(plane_xy_);
    rules(qo, &cell_);
    if (bound_) {
      qo.triangle_ok = [&](const double* a, const double* b, const double* c) {
        return bound_->ok(a, b, c, 0, 0, dem_.width() - 1, dem_.height() - 1, *cells_);
      };
    }
    // note: the merge is the serial part of qem; its first costs (about half its plans: every
    // edge of the open band), and the full costs of those likely to come up at them
    // (QemOptions::full_first_costs), are spread over the threads. The callbacks above are
    // safe from several threads (the chord test locks its transformation; triangle_ok is not
    // called).
    qo.for_ranges = [](std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192),
                        [&](const tbb::blocked_range<std::size_t>& r) { fn(r.begin(), r.end()); });
    };
    // note: on one thread the walks made ahead are more work than those they save (San Gabriel
    // to 10 %: the merge's collapse 0.223 -> 0.232 s, medians of 5 alternated runs).
    if (worker_threads() > 1) qo.full_first_costs = 2;
    return core::qem_simplify(std::move(mesh_), keep, std::move(qo), progress, max_cost);
  }

  // Vertices no later group can change: farther than kOpenRings edges from every vertex a
  // later piece's window shares.
  std::vector<char> finals(std::size_t end) const {
    const std::size_t n = cell_.size();
    // Neighbours (CSR) from the faces.
    std::vector<std::uint32_t> first(n + 1, 0);
    for (const auto& t : mesh_.faces) {
      for (const std::uint32_t v : t) first[v + 1] += 2;
    }
    for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1), adj(first[n]);
    for (const auto& t : mesh_.faces) {
      for (int k = 0; k < 3; ++k) {
        adj[next[t[k]]++] = t[(k + 1) % 3];
        adj[next[t[k]]++] = t[(k + 2) % 3];
      }
    }
    std::vector<int> ring(n, -1);
    std::vector<std::uint32_t> front;
    for (std::uint32_t v = 0; v < n; ++v) {
      if (out_id_[v] == kNone && seam_[v] && later_.later(cell_[v], end)) {
        ring[v] = 0;
        front.push_back(v);
      }
    }
    for (int k = 1; k <= kOpenRings && !front.empty(); ++k) {
      std::vector<std::uint32_t> grown;
      for (const std::uint32_t v : front) {
        for (std::uint32_t i = first[v]; i < first[v + 1]; ++i) {
          if (ring[adj[i]] >= 0) continue;
          ring[adj[i]] = k;
          grown.push_back(adj[i]);
        }
      }
      front = std::move(grown);
    }
    std::vector<char> final_vertex(n);
    for (std::size_t v = 0; v < n; ++v) final_vertex[v] = ring[v] < 0;
    return final_vertex;
  }

  // Final vertices get their output ids (in order) and are written; faces whose corners are
  // all final are written (those not counter-clockwise in the output CRS counted) and leave
  // what is open, as do final vertices left without a face.
  void write_final(const std::vector<char>& final_vertex) {
    const std::size_t n = cell_.size();
    core::TriMesh batch;
    std::vector<std::uint32_t> fresh;
    for (std::size_t v = 0; v < n; ++v) {
      if (!final_vertex[v] || out_id_[v] != kNone) continue;
      out_id_[v] = static_cast<std::uint32_t>(written_++);
      fresh.push_back(static_cast<std::uint32_t>(v));
      batch.xyz.insert(batch.xyz.end(), mesh_.xyz.begin() + 3 * v, mesh_.xyz.begin() + 3 * v + 3);
    }
    positions_.to_output(batch);
    for (std::size_t i = 0; i < fresh.size(); ++i) {
      std::copy_n(batch.xyz.begin() + 3 * i, 3, out_xyz_.begin() + 3 * fresh[i]);
    }
    std::vector<char> used(n, 0);
    std::size_t open_faces = 0;
    for (const auto& t : mesh_.faces) {
      if (out_id_[t[0]] != kNone && out_id_[t[1]] != kNone && out_id_[t[2]] != kNone) {
        batch.faces.push_back({out_id_[t[0]], out_id_[t[1]], out_id_[t[2]]});
        if (!(core::twice_area_xy(&out_xyz_[3 * t[0]], &out_xyz_[3 * t[1]], &out_xyz_[3 * t[2]]) >
              0)) {
          ++st_.folded_faces;
        }
        continue;
      }
      mesh_.faces[open_faces++] = t;
      for (const std::uint32_t v : t) used[v] = 1;
    }
    mesh_.faces.resize(open_faces);
    if (options_.sink) {
      options_.sink->add(batch.xyz, batch.faces);
    } else {
      out_.xyz.insert(out_.xyz.end(), batch.xyz.begin(), batch.xyz.end());
      out_.faces.insert(out_.faces.end(), batch.faces.begin(), batch.faces.end());
    }
    batch = {};
    // Compact what stays open.
    std::vector<std::uint32_t> id(n, kNone);
    std::size_t m = 0;
    for (std::size_t v = 0; v < n; ++v) {
      if (!used[v]) continue;
      id[v] = static_cast<std::uint32_t>(m);
      std::copy_n(mesh_.xyz.begin() + 3 * v, 3, mesh_.xyz.begin() + 3 * m);
      std::copy_n(out_xyz_.begin() + 3 * v, 3, out_xyz_.begin() + 3 * m);
      quadrics_[m] = quadrics_[v];
      if (positions_.projected)
        std::copy_n(plane_xy_.begin() + 2 * v, 2, plane_xy_.begin() + 2 * m);
      cell_[m] = cell_[v];
      seam_[m] = seam_[v];
      out_id_[m] = out_id_[v];
      ++m;
    }
    mesh_.xyz.resize(3 * m);
    out_xyz_.resize(3 * m);
    quadrics_.resize(m);
    if (positions_.projected) plane_xy_.resize(2 * m);
    cell_.resize(m);
    seam_.resize(m);
    out_id_.resize(m);
    for (auto& t : mesh_.faces) t = {id[t[0]], id[t[1]], id[t[2]]};
    for (auto* v : {&mesh_.xyz, &plane_xy_, &out_xyz_}) v->shrink_to_fit();
    mesh_.faces.shrink_to_fit();
    quadrics_.shrink_to_fit();
    cell_.shrink_to_fit();
    seam_.shrink_to_fit();
    out_id_.shrink_to_fit();
  }

  const core::RasterSource& dem_;
  const QemEngineOptions& options_;
  const Positions positions_;
  const LaterWindows later_;
  MetaStats& st_;
  std::vector<double> weight_;   // per piece (see the constructor)
  double total_ = 0, done_ = 0;  // the weights of all pieces, and of those merged
  std::vector<double> outline_;  // per piece, its vertices beside voids
  double forced_per_outline_ = 0;  // of which no collapse removes (MetaStats)
  std::optional<VerticalBound> bound_;
  const std::function<bool(std::uint64_t, std::uint64_t)> chord_ = dem_.outline_chord_test();
  std::optional<BlockCache> cells_;
  core::TriMesh mesh_;
  std::vector<core::Quadric> quadrics_;
  std::vector<std::uint64_t> cell_;
  std::vector<char> seam_;
  std::vector<double> plane_xy_;
  std::vector<std::uint32_t> out_id_;
  std::vector<double> out_xyz_;  // a final vertex's position in the output CRS
  std::size_t written_ = 0;      // vertices written
  core::TriMesh out_;
};

// The merge progress of group g of `groups`: the collapse's fraction within its share.
core::Progress group_progress(const core::Progress& progress, std::size_t g, std::size_t groups) {
  return [&progress, g, groups](double fr, std::string_view) {
    return !progress ||
           progress((static_cast<double>(g) + fr) / static_cast<double>(groups), "merge");
  };
}

}  // namespace

std::vector<std::size_t> qem_groups(const std::vector<core::Piece>& pieces, double fraction,
                                    const QemEngineOptions& options) {
  const std::size_t budget = options.merge_bytes ? options.merge_bytes : options.tile_bytes;
  const double per_vertex = std::min(1.0, options.slack * fraction) * kQemBytesPerKeptVertex;
  std::vector<std::size_t> starts;
  double held = 0;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const double bytes = per_vertex * static_cast<double>(pieces[i].vertices);
    if (starts.empty() || held + bytes > static_cast<double>(budget)) {
      starts.push_back(i);
      held = 0;
    }
    held += bytes;
  }
  starts.push_back(pieces.size());
  return starts;
}

// note: the collapse's time per vertex grows with its mesh (its queue and arrays leave the
// caches): San Gabriel resampled to 3M cells in 16 pieces of 192k, 4.5 us per cell against 3.3
// in 16 of 48k; 12M cells, 7.1. So a large DEM gets more pieces, of at most this many vertices
// (which also gives more threads work). At 1 << 16, San Gabriel itself (770k cells, 16 pieces
// of 48k) took 8.2 s of CPU to 10 % on a busy day, against 4.2 s in 64 pieces of 12k; 128 and
// 256 pieces were no faster (the merge grows). Its distance error moved by +0.8 % at 10 %.
// Pieces of DEMs up to 16 x this are as before.
constexpr std::size_t kQemPieceVertices = 1 << 14;

namespace {

// note: the pilot's pieces: every kPilotEvery-th in k-d order (spread over the DEM), at least
// kPilotLeast (all of a DEM of fewer). San Gabriel: 8 of 64 pieces.
constexpr std::size_t kPilotEvery = 32, kPilotLeast = 8;
// With several merge groups, also up to kPilotOutline pieces at least kPilotOutlineShare of
// whose vertices lie beside voids, those with the largest share first: the target is shared
// among the groups by what their pieces keep, estimated before they are simplified, and such
// a piece keeps several times what others do (kilauea_utm5 at --tile-mb 4: pieces 45 % void
// kept 60 % of their vertices, whole ones 16-21 %; its last group, the sea, kept 14,133
// vertices where the spread's mean gave 6,919, and the merge kept 70,115 of 65,734 asked).
constexpr std::size_t kPilotOutline = 4;
constexpr double kPilotOutlineShare = 0.1;

// What a piece keeps under the pilot's bound, per vertex: inner ones and those beside voids.
struct KeptModel {
  double inner = 0, outline = 0;
};
// The least-squares fit of kept = inner x a + outline x b over the pilot's pieces, a and b in
// [0, 1]; where the outline counts tell nothing (none, or in proportion to the rest) one rate
// for both.
KeptModel fit_kept(const std::vector<double>& kept, const std::vector<double>& inner,
                   const std::vector<double>& outline) {
  double ii = 0, io = 0, oo = 0, ki = 0, ko = 0, k = 0, v = 0;
  for (std::size_t j = 0; j < kept.size(); ++j) {
    ii += inner[j] * inner[j];
    io += inner[j] * outline[j];
    oo += outline[j] * outline[j];
    ki += kept[j] * inner[j];
    ko += kept[j] * outline[j];
    k += kept[j];
    v += inner[j] + outline[j];
  }
  const double rate = v > 0 ? std::clamp(k / v, 0.0, 1.0) : 0.0;
  const double det = ii * oo - io * io;
  if (!(det > 1e-6 * ii * oo)) return {rate, rate};
  KeptModel m{(ki * oo - ko * io) / det, (ko * ii - ki * io) / det};
  if (m.outline > 1 || m.outline < 0 || m.inner < 0 || m.inner > 1) {
    // On the boundary: b clamped, a refitted.
    m.outline = std::clamp(m.outline, 0.0, 1.0);
    m.inner = ii > 0 ? std::clamp((ki - m.outline * io) / ii, 0.0, 1.0) : rate;
  }
  return m;
}

// The pilot (qem_engine.hpp): a spread of the pieces simplified down to kPieceLeast x their
// shares, each collapse's cost noted; the bound is the largest cost at which they would keep,
// together, what their counts by size (slack x their shares) keep. Sets st's pilot fields.
// With outputs, the pieces whose copies (at most copy_bytes of them) it could take on to
// their outputs are there, their reports by_pilot.
void run_pilot(const core::RasterSource& dem, const QemEngineOptions& options,
               const std::vector<core::Piece>& pieces, const core::Progress& progress,
               MetaStats& st, bool groups, std::size_t copy_bytes,
               std::vector<QemPieceMesh>* outputs) {
  st.piece_cost_bound = -1;
  st.merge_cost_cap = -1;
  if (options.max_error > 0 || pieces.empty()) return;
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = pieces.size();
  const std::size_t m = std::min(n, std::max(kPilotLeast, (n + kPilotEvery - 1) / kPilotEvery));
  // The pilot's pieces: m spread over the DEM (they find the bound), then with several groups
  // those most of whose vertices lie beside voids (they tell the groups' estimates what such
  // pieces keep).
  std::vector<std::size_t> which(m);
  for (std::size_t j = 0; j < m; ++j) which[j] = (2 * j + 1) * n / (2 * m);
  if (groups) {
    std::vector<std::size_t> rough;
    for (std::size_t i = 0; i < n; ++i) {
      if (static_cast<double>(pieces[i].outline) >=
              kPilotOutlineShare * static_cast<double>(pieces[i].vertices) &&
          std::find(which.begin(), which.end(), i) == which.end())
        rough.push_back(i);
    }
    auto share_of = [&](std::size_t i) {
      return static_cast<double>(pieces[i].outline) /
             static_cast<double>(std::max<std::size_t>(1, pieces[i].vertices));
    };
    std::stable_sort(rough.begin(), rough.end(),
                     [&](std::size_t x, std::size_t y) { return share_of(x) > share_of(y); });
    rough.resize(std::min(rough.size(), kPilotOutline));
    which.insert(which.end(), rough.begin(), rough.end());
  }
  const std::size_t all = which.size();
  std::vector<PilotCurve> curves(all);
  std::vector<PieceReport> reports(all);
  const double fraction = qem_fraction(st);
  const Positions positions(dem);
  SharedProgress shared(progress, all);
  // Which pieces' collapses are copied: the first while they fit copy_bytes together.
  std::vector<char> copy(all, 0);
  for (std::size_t j = 0, left = copy_bytes; outputs && j < all; ++j) {
    const std::size_t bytes = core::piece_bytes(pieces[which[j]], 1);
    if (bytes > left || (j < m && j >= kPilotCopies)) continue;
    copy[j] = 1;
    left -= bytes;
  }
  tbb::parallel_for(std::size_t{0}, all, [&](std::size_t j) {
    shared.check();
    // Progress: the pilot's pieces done (stage "pilot"), asked within each too (a stop).
    // note: j by value: a copy of the collapse (and its progress) goes on after this task.
    pilot_piece(dem, positions, pieces[which[j]], fraction, options, reports[j],
                [&shared, j](double, std::string_view) { return shared.update(j, 0.0, "pilot"); },
                copy[j] != 0, curves[j]);
    if (!curves[j].resume) shared.update(j, 1.0, "pilot");
  });
  shared.check();
  // The bound, from the spread (the first m): kept_at falls as it grows; the largest of the
  // costs noted that keeps `want`.
  // note: a piece that keeps more than its count by size whatever a collapse may cost (the
  // outline round its voids: the least it came to) asks that much: its excess once made the
  // others' share of `want`, and a spread holding one piece of scattered voids found no bound
  // (the pieces then kept their counts by size, a rough one collapsing at any cost).
  std::size_t want = 0;
  std::vector<double> costs;
  for (std::size_t j = 0; j < m; ++j) {
    const PilotCurve& c = curves[j];
    want += std::max(c.keep, c.fewest());
    costs.insert(costs.end(), c.cost.begin(), c.cost.end());
  }
  std::sort(costs.begin(), costs.end());
  costs.erase(std::unique(costs.begin(), costs.end()), costs.end());
  // What they keep at a bound, each at least its share (floored: as the pieces are) or at
  // least kPieceLeast x it (where the merge of the whole DEM would take them, about).
  auto kept = [&](double bound, bool floored) {
    std::size_t k = 0;
    for (std::size_t j = 0; j < m; ++j) {
      const PilotCurve& c = curves[j];
      if (c.vertices) k += c.kept_at(bound, floored ? c.share : c.least);
    }
    return k;
  };
  std::size_t share = 0;  // their shares alone (1 x, not slack x)
  for (std::size_t j = 0; j < m; ++j) share += curves[j].share;
  // The largest cost noted at which they keep at least `count` (0: none does).
  auto bound_for = [&](std::size_t count, bool floored) {
    std::size_t lo = 0, hi = costs.size();  // costs[< lo] keep enough; costs[>= hi] do not
    while (lo < hi) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (kept(costs[mid], floored) >= count) {
        lo = mid + 1;
      } else {
        hi = mid;
      }
    }
    return lo;
  };
  // note: none where the least cost noted already keeps too few (a flat DEM whose collapses
  // all cost 0) or the largest still keeps enough (near 100 %: the shares are all there is):
  // the pieces keep their counts by size, as before the pilot.
  const std::size_t at = bound_for(want, true);
  st.pilot_pieces = all;
  if (at > 0 && at < costs.size()) {
    st.piece_cost_bound = costs[at - 1];
    // The merge's cap: kMergeCostCap x the cost at which they would keep their shares alone,
    // unfloored (where the merge of the whole DEM would stop, about).
    const std::size_t end = bound_for(share, false);
    if (end > 0 && costs[end - 1] > 0) st.merge_cost_cap = kMergeCostCap * costs[end - 1];
    std::vector<double> kept_by(all), inner(all), outline(all);
    for (std::size_t j = 0; j < all; ++j) {
      const PilotCurve& c = curves[j];
      // note: a piece's window holds the next pieces' first column and row: its count by its
      // own vertices.
      const double own = static_cast<double>(pieces[which[j]].vertices);
      kept_by[j] = c.vertices ? static_cast<double>(c.kept_at(st.piece_cost_bound, c.share)) *
                                    own / static_cast<double>(c.vertices)
                              : 0;
      outline[j] = static_cast<double>(std::min(pieces[which[j]].outline, pieces[which[j]].vertices));
      inner[j] = own - outline[j];
    }
    const KeptModel fit = fit_kept(kept_by, inner, outline);
    st.pilot_kept_per_inner = fit.inner;
    st.pilot_kept_per_outline = fit.outline;
    // Of those, the vertices no collapse removes: where a piece's curve stopped above its
    // least, that count (its voids' outlines), per vertex beside a void.
    double forced = 0, beside = 0;
    for (std::size_t j = 0; j < all; ++j) {
      const PilotCurve& c = curves[j];
      if (c.vertices && c.fewest() > c.least)
        forced += static_cast<double>(c.fewest()) * (inner[j] + outline[j]) /
                  static_cast<double>(c.vertices);
      beside += outline[j];
    }
    st.pilot_forced_per_outline = beside > 0 ? std::clamp(forced / beside, 0.0, 1.0) : 0.0;
  }
  // The pieces whose copies made no collapse over the bound: on from there to their outputs.
  if (outputs) outputs->resize(n);
  tbb::parallel_for(std::size_t{0}, all, [&](std::size_t j) {
    PilotCurve& c = curves[j];
    if (!c.resume) return;
    shared.check();
    const double bound = st.piece_cost_bound;
    if (bound < 0 || c.resume_cost <= bound) {
      core::QemCollapse resume = std::move(*c.resume);
      c.resume.reset();
      if (bound >= 0) {
        resume.collapse(c.share, bound);
      } else {
        resume.collapse(c.keep, kAnyCost);
      }
      const std::size_t i = which[j];
      PieceReport& report = st.pieces[i];
      report.read_s = reports[j].read_s;
      (*outputs)[i] = c.piece->finish(std::move(resume), report, nullptr);
      report.by_pilot = true;
    }
    c.resume.reset();
    c.piece.reset();
    shared.update(j, 1.0, "pilot");
  });
  shared.check();
  for (const std::size_t i : which) st.pilot_finished += st.pieces[i].by_pilot;
  st.pilot_s = seconds_since(t0);
}

}  // namespace

std::vector<core::Piece> plan_qem(const core::RasterSource& dem, const QemEngineOptions& options,
                                  const core::Progress& progress, MetaStats& st,
                                  std::vector<QemPieceMesh>* outputs) {
  const auto bytes = options.tile_bytes;
  const std::vector<core::Piece> pieces =
      divide_dem(dem, options.keep, options.levels, bytes, 1, progress, st, kQemPieceVertices);
  // The merge holds one group's kept vertices (and the open band before it), the next group's
  // pieces' outputs beside it (where there is a next group), and the output unless it goes to
  // a sink.
  const double fraction = std::min(1.0, options.slack * qem_fraction(st));
  const std::vector<std::size_t> groups = qem_groups(pieces, qem_fraction(st), options);
  double group = 0;
  for (std::size_t g = 0; g + 1 < groups.size(); ++g) {
    double n = 0;
    for (std::size_t i = groups[g]; i < groups[g + 1]; ++i)
      n += static_cast<double>(pieces[i].vertices);
    group = std::max(group, n * fraction);
  }
  const std::size_t beside = groups.size() > 2 ? kQemBytesPerPieceVertex : 0;
  const std::size_t need =
      static_cast<std::size_t>(group * static_cast<double>(kQemBytesPerKeptVertex + beside)) +
      (options.sink ? 0 : st.target_vertices * kQemBytesPerOutputVertex) +
      pieces_in_flight_bytes(pieces, 1, bytes);
  check_memory(dem, st.target_vertices, need, options.memory_limit_bytes);
  // note: after the check, which refuses a run before any piece's work. Its copies take at
  // most a tile, and no more than the check leaves of the limit.
  const std::size_t limit = options.memory_limit_bytes;
  const std::size_t copies = std::min(bytes, limit == 0 ? bytes : limit - need);
  run_pilot(dem, options, pieces, progress, st, groups.size() > 2, outputs ? copies : 0,
            outputs);
  return pieces;
}

void simplify_qem_pieces(const core::RasterSource& dem, const QemEngineOptions& options,
                         const std::vector<core::Piece>& pieces,
                         const std::vector<std::size_t>& which, MetaStats& st,
                         std::vector<QemPieceMesh>& outputs, const core::Progress& progress) {
  const double fraction = qem_fraction(st);
  const Positions positions(dem);
  outputs.resize(pieces.size());
  SharedProgress shared(progress, which.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, which.size(), 1),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k < r.end(); ++k) {
                        shared.check();
                        const std::size_t i = which[k];
                        if (st.pieces[i].by_pilot) {  // its output made by the pilot
                          shared.update(k, 1.0, "simplify");
                          continue;
                        }
                        const core::Progress piece_progress = [&](double fr, std::string_view) {
                          return shared.update(k, fr, "simplify");
                        };
                        outputs[i] = simplify_piece(dem, positions, pieces[i], fraction,
                                                    st.piece_cost_bound, options, st.pieces[i],
                                                    piece_progress);
                        shared.update(k, 1.0, "simplify");
                      }
                    });
  shared.check();
}

core::TriMesh simplify_qem(const core::RasterSource& dem, const QemEngineOptions& options,
                           const core::Progress& progress, MetaStats* stats) {
  MetaStats local;
  MetaStats& st = stats ? *stats : local;
  // 1. Count surface vertices per block, streaming; divide.
  // The pilot's pieces' outputs come from it (most of them).
  std::vector<QemPieceMesh> outputs;
  const std::vector<core::Piece> pieces = plan_qem(dem, options, progress, st, &outputs);
  // 2 and 3, a group of pieces at a time: simplify its pieces concurrently, seams locked; then
  // stitch them to what is open and collapse on.
  const std::vector<std::size_t> groups = qem_groups(pieces, qem_fraction(st), options);
  st.merge_groups = groups.size() - 1;
  QemSweep sweep(dem, options, pieces, st);
  outputs.resize(pieces.size());
  const double all = static_cast<double>(std::max<std::size_t>(1, pieces.size()));
  if (groups.size() < 2) return sweep.finish();  // no pieces
  const std::size_t last = groups.size() - 2;
  // note: one group's merge runs beside the next group's pieces: it is serial, a sixth of the
  // CPU on 19M cells (12 of 74 s), and the output is the same bytes (each merge waits for the
  // one before and needs only its own group's pieces). 19M cells at 2 threads: 43 -> 38 s.
  // Both report as "simplify", through one lock, the merge repeating the pieces' last fraction,
  // until the last group's merge.
  std::mutex report;
  double reported = 0;
  auto simplify_progress = [&](double f) {
    std::lock_guard<std::mutex> hold(report);
    reported = std::max(reported, f);
    return !progress || progress(reported, "simplify");
  };
  const core::Progress merge_beside = [&](double, std::string_view) {
    return simplify_progress(0);
  };
  auto simplify_group = [&](std::size_t first, std::size_t end) {
    std::vector<std::size_t> which(end - first);
    for (std::size_t i = first; i < end; ++i) which[i - first] = i;
    const auto t0 = std::chrono::steady_clock::now();
    simplify_qem_pieces(dem, options, pieces, which, st, outputs, [&](double fr, std::string_view) {
      return simplify_progress(
          (static_cast<double>(first) + fr * static_cast<double>(end - first)) / all);
    });
    st.simplify_s += seconds_since(t0);
    if (first == 0) st.peak_rss_before_merge_kb = peak_rss_kb();
    // note: once a group, not after each piece: a piece's freed scratch serves the next piece
    // on its thread, where a trim after each handed it back to the kernel and the next piece
    // faulted it in again (San Gabriel to 10 %, 64 pieces: 0.25 s of system time, 10 % of the
    // CPU). Not after the last group: the merge that follows takes that memory up again, and
    // each page the kernel hands back costs a fault (about 11 us on these machines).
    if (end < pieces.size()) release_free_memory();
    // The most one group's outputs held (the merge beside them took the group before's into
    // its mesh first).
    std::size_t group_bytes = 0;
    for (std::size_t i = first; i < end; ++i) group_bytes += outputs[i].bytes();
    st.kept_bytes = std::max(st.kept_bytes, group_bytes);
  };
  double merge_s = 0;              // written by the merge task, read after its wait
  std::exception_ptr merge_error;  // the same
  const bool beside = worker_threads() > 1;
  tbb::task_group merging;
  // The group before merged: its exception, if any, thrown here.
  auto merged = [&] {
    merging.wait();
    if (merge_error) std::rethrow_exception(merge_error);
  };
  try {
    for (std::size_t g = 0; g < last; ++g) {
      const std::size_t first = groups[g], end = groups[g + 1];
      simplify_group(first, end);
      merged();
      auto merge = [&, first, end] {
        try {
          const auto t1 = std::chrono::steady_clock::now();
          sweep.add(outputs, pieces, first, end, merge_beside);
          merge_s += seconds_since(t1);
        } catch (...) {
          merge_error = std::current_exception();
        }
      };
      // note: on one thread the merge would only wait for the next group's pieces, holding
      // their outputs too (19M cells: 299 -> 414 MB): it runs now, as it did before.
      if (beside) {
        merging.run(merge);
      } else {
        merge();
        merged();
      }
    }
    simplify_group(groups[last], groups[last + 1]);
    merged();
  } catch (...) {
    // note: a stop (or error) in the pieces waits for the merge beside them, which uses them.
    merging.wait();
    throw;
  }
  const auto t1 = std::chrono::steady_clock::now();
  if (progress && !progress(static_cast<double>(last) / (last + 1), "merge")) throw Cancelled();
  sweep.add(outputs, pieces, groups[last], groups[last + 1],
            group_progress(progress, last, last + 1));
  st.merge_s = merge_s + seconds_since(t1);
  st.kept_vertices = sweep.vertices_written();
  return sweep.finish();
}

core::TriMesh merge_qem(const core::RasterSource& dem, const QemEngineOptions& options,
                        const std::vector<core::Piece>& pieces, std::vector<QemPieceMesh>& outputs,
                        MetaStats& st, const core::Progress& progress) {
  st.peak_rss_before_merge_kb = peak_rss_kb();
  for (const auto& o : outputs) st.kept_bytes += o.bytes();
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<std::size_t> groups = qem_groups(pieces, qem_fraction(st), options);
  st.merge_groups = groups.size() - 1;
  QemSweep sweep(dem, options, pieces, st);
  for (std::size_t g = 0; g + 1 < groups.size(); ++g) {
    if (progress && !progress(static_cast<double>(g) / (groups.size() - 1), "merge")) {
      throw Cancelled();
    }
    sweep.add(outputs, pieces, groups[g], groups[g + 1],
              group_progress(progress, g, groups.size() - 1));
  }
  st.kept_vertices = sweep.vertices_written();
  st.merge_s = seconds_since(t0);
  return sweep.finish();
}

namespace {

// note: the bytes of a machine to another of the same build (dpts-mpi's ranks): arrays as they
// lie in memory, each after its length.
template <typename T>
void put(std::string& out, const T* data, std::size_t n) {
  const std::uint64_t len = n;
  out.append(reinterpret_cast<const char*>(&len), sizeof(len));
  out.append(reinterpret_cast<const char*>(data), n * sizeof(T));
}

template <typename T>
void take(const std::string& in, std::size_t& at, std::vector<T>& v) {
  std::uint64_t len = 0;
  if (in.size() - at < sizeof(len)) throw std::runtime_error("qem piece bytes: truncated");
  std::memcpy(&len, in.data() + at, sizeof(len));
  at += sizeof(len);
  if (len > (in.size() - at) / sizeof(T)) throw std::runtime_error("qem piece bytes: truncated");
  v.resize(len);
  std::memcpy(v.data(), in.data() + at, len * sizeof(T));
  at += len * sizeof(T);
}

}  // namespace

std::string to_bytes(const QemPieceMesh& m, const PieceReport& report) {
  std::string out;
  const double rep[2] = {report.read_s, report.simplify_s};
  const std::uint64_t counts[2] = {report.budget, report.kept};
  put(out, counts, 2);
  put(out, rep, 2);
  put(out, m.mesh.xyz.data(), m.mesh.xyz.size());
  put(out, m.mesh.faces.data(), m.mesh.faces.size());
  put(out, m.quadrics.data(), m.quadrics.size());
  put(out, m.cell.data(), m.cell.size());
  put(out, m.seam.data(), m.seam.size());
  put(out, m.plane_xy.data(), m.plane_xy.size());
  return out;
}

void from_bytes(const std::string& in, QemPieceMesh& m, PieceReport& report) {
  std::size_t at = 0;
  std::vector<std::uint64_t> counts;
  std::vector<double> rep;
  take(in, at, counts);
  take(in, at, rep);
  take(in, at, m.mesh.xyz);
  take(in, at, m.mesh.faces);
  take(in, at, m.quadrics);
  take(in, at, m.cell);
  take(in, at, m.seam);
  take(in, at, m.plane_xy);
  const std::size_t n = m.cell.size();
  if (counts.size() != 2 || rep.size() != 2 || at != in.size() || m.mesh.xyz.size() != 3 * n ||
      m.quadrics.size() != n || m.seam.size() != n ||
      (!m.plane_xy.empty() && m.plane_xy.size() != 2 * n)) {
    throw std::runtime_error("qem piece bytes: inconsistent");
  }
  for (const auto& f : m.mesh.faces) {
    if (f[0] >= n || f[1] >= n || f[2] >= n) throw std::runtime_error("qem piece bytes: bad face");
  }
  report.budget = counts[0];
  report.kept = counts[1];
  report.read_s = rep[0];
  report.simplify_s = rep[1];
}

}  // namespace dpts::par

// The elimination method on a CGAL Delaunay TIN, with VP or PLD importance
// ("Distance Preserving Terrain Simplification", the paper in ../shared/paper, sections 3.1,
// 4.1 and 4.2).
//
// The footprint stays exact because every outline edge of the footprint between two
// neighbouring cells is Delaunay in any subset of the grid's cells (an empty circle through
// its ends exists), so Delaunay faces never cross the outline and each face is wholly inside
// or outside it; faces are labelled by an exact centroid test in grid space. An outline
// vertex is removed only where the outline is straight through it and the straight edge is
// Delaunay afterwards; once in, an edge stays Delaunay while its ends remain.
//
// To know the importance of a vertex before removing it, its removal is simulated: the hole
// is refilled with the Delaunay triangulation of the link, using CGAL's own symbolically
// perturbed in-circle test, so the simulated triangles are exactly those CGAL's remove()
// produces (the perturbed Delaunay triangulation is unique).
#include "core/elimination.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Spatial_sort_traits_adapter_2.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/property_map.h>
#include <CGAL/spatial_sort.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/errors.hpp"
#include "core/footprint.hpp"
#include "core/importance.hpp"
#include "core/indexed_heap.hpp"

namespace dpts::core {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
struct FaceLabel {
  std::int8_t inside = -1;  // 1 inside the footprint, 0 outside, -1 not yet known
};
// Everything the hot loops read about a vertex lives in the vertex itself (fewer cache misses).
struct VertexInfo {
  std::uint32_t id = 0;     // surface vertex id
  std::uint32_t stamp = 0;  // last removal whose link held this vertex
  std::int32_t col = 0, row = 0;
  double z = 0;  // height, metres
};
using Vb = CGAL::Triangulation_vertex_base_with_info_2<VertexInfo, K>;
using Fb = CGAL::Triangulation_face_base_with_info_2<FaceLabel, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
using VertexHandle = Delaunay::Vertex_handle;
using FaceHandle = Delaunay::Face_handle;
using Point = K::Point_2;

constexpr double kLocked = std::numeric_limits<double>::infinity();

std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  std::uint64_t h = a * 0x9E3779B97F4A7C15ull ^ (b + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
  h ^= (c + 0x165667B19E3779F9ull) * 0x27D4EB2F165667C5ull;
  return h ^ (h >> 29);
}

// Per-call working memory of evaluate().
struct Scratch {
  std::vector<VertexHandle> ring;  // link of the vertex, counter-clockwise
  std::vector<char> inside;        // inside[j]: face ring[j] -> ring[j+1] is in the footprint
  std::vector<VertexHandle> poly;  // polygon to refill (whole ring or the inside chain)
  std::vector<Point3> pts;         // poly in metres
  std::vector<LinkTriangle> tris;  // refill triangles, indices into poly
  std::vector<std::pair<int, int>> todo;
};

}  // namespace

struct Eliminator::Impl {
  const HeightGrid& grid;
  FootprintIndex footprint;
  GridFrame frame;
  EliminationOptions options;
  std::vector<std::uint32_t> cells;        // surface vertex id -> cell index
  std::vector<VertexHandle> handle;        // id -> vertex (null once removed)
  std::vector<double> initial;             // importance from compute_importance()
  std::vector<std::uint32_t> evaluations;  // per-vertex counter, seeds Monte Carlo VP
  // Whether a vertex's key in the heap is its importance (1) or a lower bound of it (0).
  std::vector<char> exact_key;
  IndexedMinHeap heap;
  bool heap_ready = false;
  std::uint32_t removals = 0;  // removals so far, all eliminate() calls together
  Delaunay dt;
  std::size_t alive = 0;

  double inv[2][2];  // frame (u, w) -> grid (col, row)

  Impl(const HeightGrid& g, const GridFrame& f, const EliminationOptions& o)
      : grid(g), footprint(g), frame(f), options(o) {
    f.inverse(inv);
  }

  Point3 metric(VertexHandle v) const {
    const double s = frame.metres_per_unit;
    return {s * v->point().x(), s * v->point().y(), v->info().z};
  }

  std::int8_t label(FaceHandle f) const {
    std::int64_t sc = 0, sr = 0;
    for (int i = 0; i < 3; ++i) {
      sc += f->vertex(i)->info().col;
      sr += f->vertex(i)->info().row;
    }
    return footprint.contains_third(sc, sr) ? 1 : 0;
  }

  // Delaunay refill of poly[lo..hi], closed by the edge poly[hi] -> poly[lo] with the
  // polygon on its left. Appends counter-clockwise triangles; the first one appended is the
  // one on the closing edge. Returns false on a degenerate (collinear) polygon.
  bool refill(Scratch& s) const {
    s.tris.clear();
    s.todo.assign(1, {0, static_cast<int>(s.poly.size()) - 1});
    while (!s.todo.empty()) {
      const auto [lo, hi] = s.todo.back();
      s.todo.pop_back();
      if (hi - lo < 2) continue;
      const Point& a = s.poly[hi]->point();
      const Point& b = s.poly[lo]->point();
      int best = -1;
      for (int c = lo + 1; c < hi; ++c) {
        const Point& p = s.poly[c]->point();
        if (CGAL::orientation(a, b, p) != CGAL::LEFT_TURN) continue;
        if (best < 0 || dt.side_of_oriented_circle(a, b, s.poly[best]->point(), p, true) ==
                            CGAL::ON_POSITIVE_SIDE) {
          best = c;
        }
      }
      if (best < 0) return false;
      s.tris.push_back({hi, lo, best});
      s.todo.push_back({best, hi});
      s.todo.push_back({lo, best});
    }
    return true;
  }

  // Whether the chord poly.front() - poly.back() about to replace an outline vertex has a circle
  // through its ends that is empty in this TIN and lies in options.chord_box (see there). The
  // circles through a and b have centres m + t n (m the chord's middle, n its unit normal away
  // from the inner apex r); a vertex q on the inner side is outside the circle iff t > t_q, one
  // on the far side iff t < t_q. Take the t in the open empty range nearest 0 (the smallest
  // circle), with a relative margin for rounding, and test the circle against the box in grid
  // space.
  bool witness_in_box(const Scratch& s, std::size_t first, const Point& pr) const {
    const Point& pa = s.poly.front()->point();
    const Point& pb = s.poly.back()->point();
    const double mx = 0.5 * (pa.x() + pb.x()), my = 0.5 * (pa.y() + pb.y());
    const double dx = pb.x() - pa.x(), dy = pb.y() - pa.y();
    const double len = std::hypot(dx, dy);
    double nx = -dy / len, ny = dx / len;
    if ((pr.x() - mx) * nx + (pr.y() - my) * ny > 0) nx = -nx, ny = -ny;
    const double quarter = 0.25 * len * len;
    double lo = -std::numeric_limits<double>::infinity();
    double hi = std::numeric_limits<double>::infinity();
    auto bound = [&](const Point& q) {
      const double qx = q.x() - mx, qy = q.y() - my;
      const double side = qx * nx + qy * ny;
      const double power = qx * qx + qy * qy - quarter;
      if (side == 0) {
        if (power < 0) lo = 1, hi = -1;  // on the chord itself: no circle
        return;
      }
      const double t = power / (2 * side);
      if (side < 0) {
        lo = std::max(lo, t);
      } else {
        hi = std::min(hi, t);
      }
    };
    bound(pr);
    const std::size_t n = s.ring.size();
    for (std::size_t j = (first + s.poly.size()) % n; j != first; j = (j + 1) % n) {
      const VertexHandle q = s.ring[j];
      if (q == s.poly.front() || q == s.poly.back() || dt.is_infinite(q)) continue;
      bound(q->point());
    }
    const double tol = 1e-7 * len;
    lo += tol, hi -= tol;
    if (!(lo <= hi)) return false;
    const double t = std::clamp(0.0, lo, hi);
    const double radius = std::sqrt(quarter + t * t);
    const double cx = mx + t * nx, cy = my + t * ny;
    // Grid position of the centre, and the circle's extent in columns and rows.
    const double col = inv[0][0] * cx + inv[0][1] * cy, row = inv[1][0] * cx + inv[1][1] * cy;
    const double col_r = radius * std::hypot(inv[0][0], inv[0][1]);
    const double row_r = radius * std::hypot(inv[1][0], inv[1][1]);
    const auto& box = *options.chord_box;
    const double margin = 1e-6;
    return col - col_r >= box.col_lo + margin && col + col_r <= box.col_hi - margin &&
           row - row_r >= box.row_lo + margin && row + row_r <= box.row_hi - margin;
  }

  // The link of v, counter-clockwise, into s.ring, and in s.inside whether each face
  // v -> ring[j] -> ring[j+1] is in the footprint. With relabel_mark != 0, first relabels the
  // incident faces whose three corners carry that stamp (new faces of a hole).
  void read_ring(VertexHandle v, Scratch& s, std::uint32_t relabel_mark) {
    s.ring.clear();
    s.inside.clear();
    auto fc = dt.incident_faces(v);
    const auto done = fc;
    do {
      const int i = fc->index(v);
      if (relabel_mark != 0 && fc->vertex(0)->info().stamp == relabel_mark &&
          fc->vertex(1)->info().stamp == relabel_mark &&
          fc->vertex(2)->info().stamp == relabel_mark && !dt.is_infinite(fc)) {
        fc->info().inside = label(fc);
      }
      s.ring.push_back(fc->vertex(Delaunay::ccw(i)));
      // note: the ring's points are read next (the refill's predicates, the star's heights),
      // each vertex's first touch a cache miss: asked for now, all of them at once.
      __builtin_prefetch(&s.ring.back()->point());
      s.inside.push_back(!dt.is_infinite(fc) && fc->info().inside == 1);
    } while (++fc != done);
  }

  // Number of runs of inside faces round the ring (0 when all or none are inside), and the
  // first face of the last run.
  static std::size_t inside_runs(const Scratch& s, std::size_t& first) {
    const std::size_t n = s.ring.size();
    std::size_t runs = 0;
    for (std::size_t j = 0; j < n; ++j) {
      if (s.inside[j] && !s.inside[(j + n - 1) % n]) ++runs, first = j;
    }
    return runs;
  }

  // The end of the inside run starting at `first`: the ring index after its last face.
  static std::size_t run_end(const Scratch& s, std::size_t first) {
    std::size_t j = first;
    while (s.inside[j]) j = (j + 1) % s.ring.size();
    return j;
  }

  // v's removal for the log: on the outline, the ends of the inside run of faces round it.
  Removal removal(VertexHandle v, Scratch& s) {
    Removal r;
    r.cell = cells[v->info().id];
    read_ring(v, s, 0);
    std::size_t first = 0;
    if (inside_runs(s, first) > 0) {
      r.outline = true;
      r.next = cells[s.ring[first]->info().id];
      r.prev = cells[s.ring[run_end(s, first)]->info().id];
    }
    return r;
  }

  // Importance of v, or kLocked when v must stay (a corner or bend of the outline, or an
  // outline vertex whose removal would change the footprint). With relabel_mark != 0, first
  // relabels the incident faces whose three corners carry that stamp (new faces of a hole).
  // With deferred given and exact VP, gives vp_volume_bound (cheaper, no more than the
  // importance) instead when that is above defer_above, and says so in *deferred.
  double evaluate(VertexHandle v, Scratch& s, std::uint32_t relabel_mark = 0,
                  double defer_above = 0, bool* deferred = nullptr) {
    if (deferred) *deferred = false;
    read_ring(v, s, relabel_mark);
    const std::size_t n = s.ring.size();
    if (!options.pinned.empty() && options.pinned[cells[v->info().id]]) return kLocked;
    const std::size_t n_inside =
        static_cast<std::size_t>(std::count(s.inside.begin(), s.inside.end(), 1));
    if (n_inside == 0) return kLocked;

    bool closed = n_inside == n;
    std::size_t first = 0;  // first inside face of the (single) inside run
    if (closed) {
      // From the link's least id: the refill's triangles and the importance's sums then come
      // in an order fixed by the star alone.
      const auto least = std::min_element(s.ring.begin(), s.ring.end(), [](VertexHandle a, VertexHandle b) { return a->info().id < b->info().id; });
      s.poly.assign(least, s.ring.end());
      s.poly.insert(s.poly.end(), s.ring.begin(), least);
    } else {
      if (inside_runs(s, first) != 1) return kLocked;  // the footprint pinches at v
      s.poly.clear();
      const std::size_t end = run_end(s, first);
      for (std::size_t j = first; j != end; j = (j + 1) % n) s.poly.push_back(s.ring[j]);
      s.poly.push_back(s.ring[end]);
      // The outline runs a -> v -> b; it must be straight (in grid space) through v.
      const VertexInfo &a = s.poly.front()->info(), &b = s.poly.back()->info(), &c = v->info();
      const std::int64_t ax = a.col - c.col, ay = a.row - c.row;
      const std::int64_t bx = b.col - c.col, by = b.row - c.row;
      if (ax * by - ay * bx != 0 || ax * bx + ay * by >= 0) return kLocked;
      if (options.outline_chord_ok && !options.outline_chord_ok(cells[a.id], cells[b.id])) {
        return kLocked;
      }
    }
    if (s.poly.size() < 3) return kLocked;

    const bool need_refill = options.importance == Importance::vp || !closed;
    if (need_refill && !refill(s)) return kLocked;
    if (!closed) {
      // The straight outline edge a-b must be Delaunay after the removal: no link vertex
      // beyond it may lie in the circle of its inner triangle.
      const Point& pa = s.poly.front()->point();
      const Point& pb = s.poly.back()->point();
      const Point& pr = s.poly[s.tris.front()[2]]->point();
      for (std::size_t j = (first + s.poly.size()) % n; j != first; j = (j + 1) % n) {
        const VertexHandle q = s.ring[j];
        if (q == s.poly.front() || q == s.poly.back() || dt.is_infinite(q)) continue;
        if (dt.side_of_oriented_circle(pb, pa, pr, q->point(), true) == CGAL::ON_POSITIVE_SIDE) {
          return kLocked;
        }
      }
      if (options.chord_box && !witness_in_box(s, first, pr)) return kLocked;
    }

    s.pts.clear();
    for (const VertexHandle& p : s.poly) s.pts.push_back(metric(p));
    const Star star{metric(v), s.pts.data(), s.pts.size(), closed};
    if (options.importance == Importance::pld) return pld_importance(star);
    if (options.vp_volume == VolumeMethod::monte_carlo) {
      const std::uint32_t id = v->info().id;
      return vp_volume_monte_carlo(star, s.tris, options.vp_samples,
                                   mix_seed(options.seed, cells[id], evaluations[id]++));
    }
    if (deferred) {
      const double bound = vp_volume_bound(star, s.tris);
      if (bound > defer_above) {
        *deferred = true;
        return bound;
      }
    }
    return vp_volume_exact(star, s.tris);
  }

  // Whether evaluate() after a removal may give a lower bound (see eliminate()).
  bool lazy() const {
    return options.lazy_vp && options.importance == Importance::vp &&
           options.vp_volume == VolumeMethod::exact;
  }
};

Eliminator::Eliminator(const HeightGrid& grid, const GridFrame& frame,
                       const EliminationOptions& options, const Progress& progress)
    : impl_(std::make_unique<Impl>(grid, frame, options)) {
  Impl& m = *impl_;
  m.cells = surface_cells(grid);
  if (m.cells.size() < 3) {
    throw std::invalid_argument(kNothingToTriangulate);
  }
  std::vector<Point> points;
  std::vector<VertexInfo> infos;
  points.reserve(m.cells.size());
  infos.reserve(m.cells.size());
  for (std::uint32_t id = 0; id < m.cells.size(); ++id) {
    VertexInfo info;
    info.id = id;
    info.col = static_cast<std::int32_t>(m.cells[id] % grid.width);
    info.row = static_cast<std::int32_t>(m.cells[id] / grid.width);
    info.z = grid.z[m.cells[id]];
    points.emplace_back(frame.u(info.col, info.row), frame.w(info.col, info.row));
    infos.push_back(info);
  }
  // CGAL's range insertion with info (Delaunay_triangulation_2::insert_with_info), written
  // out so that progress can stop it: the same spatial sort and hinted insertions, so the
  // same triangulation (on a grid, cocircular points make it depend on the order).
  std::vector<std::size_t> order(points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  using Traits = CGAL::Spatial_sort_traits_adapter_2<K, CGAL::Pointer_property_map<Point>::type>;
  CGAL::spatial_sort(order.begin(), order.end(),
                     Traits(CGAL::make_property_map(points), m.dt.geom_traits()));
  Delaunay::Face_handle hint;
  for (std::size_t k = 0; k < order.size(); ++k) {
    if (k % 65536 == 65535 && progress &&
        !progress(static_cast<double>(k) / static_cast<double>(order.size()), "triangulate")) {
      throw Cancelled();
    }
    const VertexHandle v = m.dt.insert(points[order[k]], hint);
    if (v != VertexHandle()) {
      v->info() = infos[order[k]];
      hint = v->face();
    }
  }
  points = {};
  infos = {};
  order = {};
  if (m.dt.dimension() < 2) throw std::invalid_argument("all valid cells are collinear");
  m.handle.assign(m.cells.size(), VertexHandle());
  for (auto v = m.dt.finite_vertices_begin(); v != m.dt.finite_vertices_end(); ++v) {
    m.handle[v->info().id] = v;
  }
  for (auto f = m.dt.finite_faces_begin(); f != m.dt.finite_faces_end(); ++f) {
    f->info().inside = m.label(f);
  }
  m.alive = m.cells.size();
  m.initial.assign(m.cells.size(), kLocked);
  m.evaluations.assign(m.cells.size(), 0);
  m.exact_key.assign(m.cells.size(), 1);
  m.heap = IndexedMinHeap(m.cells.size());
}

Eliminator::~Eliminator() = default;

std::size_t Eliminator::vertex_count() const { return impl_->cells.size(); }
std::size_t Eliminator::alive_count() const { return impl_->alive; }

void Eliminator::compute_importance(std::size_t begin, std::size_t end) {
  Scratch scratch;
  // A lower bound now, the importance when needed (see eliminate()).
  bool deferred = false;
  bool* const defer = impl_->lazy() ? &deferred : nullptr;
  for (std::size_t id = begin; id < end; ++id) {
    impl_->initial[id] = impl_->evaluate(impl_->handle[id], scratch, 0, -1.0, defer);
    impl_->exact_key[id] = !deferred;
  }
}

void Eliminator::eliminate(std::size_t keep, const Progress& progress, std::vector<Removal>* log) {
  Impl& m = *impl_;
  if (!m.heap_ready) {
    m.heap_ready = true;
    std::vector<std::uint32_t> ids;
    std::vector<double> keys;
    for (std::uint32_t id = 0; id < m.cells.size(); ++id) {
      if (m.handle[id] != VertexHandle() && m.initial[id] != kLocked) {
        ids.push_back(id);
        keys.push_back(m.initial[id]);
      }
    }
    m.heap.assign(ids, keys);
    m.initial = {};
  }
  const std::size_t start = m.alive;
  const double span = start > keep ? static_cast<double>(start - keep) : 1.0;
  Scratch scratch;
  std::vector<VertexHandle> link;
  std::size_t removed = 0;
  bool deferred = false;
  bool* const defer = m.lazy() ? &deferred : nullptr;
  while (m.alive > keep && !m.heap.empty()) {
    // Lazy exact VP: a vertex's key may be a lower bound of its importance; when it reaches
    // the top, the importance itself is computed and the key raised (the star is unchanged
    // since: a change would have set a new key). The vertex removed is a top whose key is
    // exact, so every other importance is at least its key (ties go by id as before), and
    // the removals come in the same order as with every importance computed at once.
    // note: nearly all such tops sink again (99 % on San Gabriel to 10 %): half the bounds
    // there are within 10 % of the importance, but the keys at the top lie closer than that.
    const std::uint32_t top = m.heap.top();
    if (!m.exact_key[top]) {
      m.exact_key[top] = 1;
      const double importance = m.evaluate(m.handle[top], scratch);
      assert(importance != kLocked && importance >= m.heap.top_key());
      m.heap.set(top, importance);
      continue;
    }
    const std::uint32_t id = m.heap.pop();  // top
    const VertexHandle v = m.handle[id];
    if (log) log->push_back(m.removal(v, scratch));
    link.clear();
    auto vc = m.dt.incident_vertices(v);
    const auto done = vc;
    do {
      if (!m.dt.is_infinite(vc)) link.push_back(vc);
    } while (++vc != done);
    m.dt.remove(v);
    m.handle[id] = VertexHandle();
    --m.alive;
    // The new faces fill the hole, so all their corners are in the link. note: remove() may
    // reuse the memory of old faces for new ones, so their labels are stale, not unset.
    const std::uint32_t mark = ++m.removals;  // over all calls: marks never repeat
    for (const VertexHandle& u : link) {
      u->info().stamp = mark;
      m.heap.prefetch_slot(u->info().id);
    }
    // note: the heap (San Gabriel: 770k entries, 12 MB) is mostly out of the caches, and its
    // slot and entry of each link vertex were the eliminator's most stalled loads: asked for
    // ahead, while the vertex's importance is computed.
    for (const VertexHandle& u : link) {
      m.heap.prefetch(u->info().id);
      // note: evaluating u relabels the new faces round u before reading their labels, and
      // every new face has a corner in the link, so all of them are relabelled in time.
      // A bound no higher than the top's key would come up next: its importance is computed
      // now, while the star is at hand (fewer cycles than deferring it, or deferring those up
      // to twice the top's key, by cachegrind's count).
      const double importance =
          m.evaluate(u, scratch, mark, m.heap.empty() ? 0.0 : m.heap.top_key(), defer);
      m.exact_key[u->info().id] = !deferred;
      if (importance == kLocked) {
        m.heap.erase(u->info().id);
      } else {
        m.heap.set(u->info().id, importance);
      }
    }
    if (++removed % 4096 == 0 && progress && !progress(removed / span, "simplify")) {
      throw Cancelled();
    }
  }
  if (progress && !progress(1.0, "simplify")) throw Cancelled();
}

Tin Eliminator::tin() const {
  const Impl& m = *impl_;
  Tin tin;
  std::vector<std::uint32_t> out_index(m.cells.size(), IndexedMinHeap::kAbsent);
  for (std::uint32_t id = 0; id < m.cells.size(); ++id) {
    if (m.handle[id] == VertexHandle()) continue;
    out_index[id] = static_cast<std::uint32_t>(tin.cells.size());
    tin.cells.push_back(m.cells[id]);  // ids ascend with cells, so cells stay sorted
  }
  for (auto f = m.dt.finite_faces_begin(); f != m.dt.finite_faces_end(); ++f) {
    if (f->info().inside != 1) continue;
    std::array<std::uint32_t, 3> t{out_index[f->vertex(0)->info().id],
                                   out_index[f->vertex(1)->info().id],
                                   out_index[f->vertex(2)->info().id]};
    std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
    tin.faces.push_back(t);
  }
  std::sort(tin.faces.begin(), tin.faces.end());
  return tin;
}

const std::vector<std::uint32_t>& Eliminator::cells() const { return impl_->cells; }
bool Eliminator::alive(std::size_t id) const { return impl_->handle[id] != VertexHandle(); }

std::vector<OutlineEdge> Eliminator::outline_edges() const {
  const Impl& m = *impl_;
  std::vector<OutlineEdge> out;
  for (auto f = m.dt.finite_faces_begin(); f != m.dt.finite_faces_end(); ++f) {
    if (f->info().inside != 1) continue;
    for (int i = 0; i < 3; ++i) {
      const FaceHandle g = f->neighbor(i);
      if (!m.dt.is_infinite(g) && g->info().inside == 1) continue;
      out.push_back({m.cells[f->vertex(Delaunay::ccw(i))->info().id],
                     m.cells[f->vertex(Delaunay::cw(i))->info().id]});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace dpts::core

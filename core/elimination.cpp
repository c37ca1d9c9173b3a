// The elimination method on a Delaunay TIN, with VP or PLD importance
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
// The Delaunay triangulation of the grid's cells comes straight from the grid where every
// cell is valid (grid_links), else from CGAL's insertion; the removals then run on a flat
// structure of our own: each vertex's link (its neighbours counter-clockwise, the infinite
// vertex among them on the convex hull, each with whether the face after it is in the
// footprint), in its own 64-byte block (longer links in a spill pool). A removal refills the hole
// with the Delaunay triangulation of the link, using CGAL's own symbolically perturbed in-circle
// test, so the triangles are exactly those CGAL's remove() makes (the perturbed Delaunay
// triangulation is unique), and the same refill, simulated, gives the importance before the
// removal. Reading a link is then one block and the link's points, where CGAL's face walk took a
// cache miss a face (perf: the walk was a third of vp's time).
#include "core/elimination.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Spatial_sort_traits_adapter_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <CGAL/property_map.h>
#include <CGAL/spatial_sort.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "core/errors.hpp"
#include "core/footprint.hpp"
#include "core/importance.hpp"
#include "core/indexed_heap.hpp"
#include "core/predicates.hpp"

namespace dpts::core {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
using VertexHandle = Delaunay::Vertex_handle;
using Point = K::Point_2;

constexpr double kLocked = std::numeric_limits<double>::infinity();

// A link entry: the neighbour's id, and in the top bit whether the face (vertex, this
// neighbour, the next one) is in the footprint.
constexpr std::uint32_t kInsideBit = 0x80000000u;
constexpr std::uint32_t kIdMask = 0x7FFFFFFFu;
constexpr std::uint32_t kInfinite = kIdMask;  // the infinite vertex (outside the convex hull)

// Everything the hot loops read about a vertex, in 32 bytes.
struct Vertex {
  Point p;       // frame units
  double z = 0;  // height, metres
  std::int32_t col = 0, row = 0;
};

// A vertex's link: in its home block, one cache line, while it has at most kHomeLinks
// neighbours (San Gabriel to 10 %: always), else in the spill pool, the home block then
// holding where (spill_at) and how much room (spill_capacity).
constexpr std::uint32_t kHomeLinks = 15;
constexpr std::uint32_t kSpilled = 0x80000000u;
// Whether the vertex's key in the queue is its importance (set) or a lower bound of it: with
// the link, so that the queue's top costs one cache miss, not two.
constexpr std::uint32_t kExactKey = 0x40000000u;
struct alignas(64) Home {
  std::uint32_t size = 0;  // neighbours (0 once removed), with kSpilled and kExactKey
  std::uint32_t e[kHomeLinks] = {};
  std::uint64_t spill_at() const { return e[0] | std::uint64_t{e[1]} << 32; }
  std::uint32_t spill_capacity() const { return e[2]; }
};

std::uint64_t mix_seed(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  std::uint64_t h = a * 0x9E3779B97F4A7C15ull ^ (b + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
  h ^= (c + 0x165667B19E3779F9ull) * 0x27D4EB2F165667C5ull;
  return h ^ (h >> 29);
}

// A triangle made by a removal, counter-clockwise, and whether it is in the footprint.
struct NewFace {
  std::uint32_t v[3];
  bool inside;
};

// Per-call working memory of evaluate() and remove().
struct Scratch {
  std::vector<std::uint32_t> ring;  // link of the vertex, counter-clockwise
  std::vector<char> inside;         // inside[j]: face ring[j] -> ring[j+1] is in the footprint
  std::vector<std::uint32_t> poly;  // polygon to refill (whole ring or the inside chain)
  std::vector<Point3> pts;          // poly in metres
  std::vector<LinkTriangle> tris;   // refill triangles, indices into poly
  std::vector<std::pair<int, int>> todo;
  std::vector<std::uint32_t> outer;      // an outline vertex's outer polygon, b .. a
  std::vector<LinkTriangle> outer_tris;  // its refill
  std::vector<NewFace> faces;            // a removal's new faces
  std::vector<std::uint32_t> splice;     // a link's new stretch
  std::vector<std::uint32_t> moved;      // a link being moved to the spill pool
  // With memo: the last refill's polygon (its points less its first, where those differences
  // are exact) and its result (see refill()).
  bool memo = false;
  bool memo_valid = false;
  std::vector<Point> memo_offsets;
  std::vector<LinkTriangle> memo_tris;
  bool memo_ok = false;
};

// Whether b - a is exact in doubles (Knuth's two-difference: its rounding error is 0).
bool exact_difference(double b, double a) {
  const double d = b - a, bv = d - b, av = d - bv;
  return (b - av) + (-a - bv) == 0;
}

}  // namespace

struct Eliminator::Impl {
  const HeightGrid& grid;
  FootprintIndex footprint;
  GridFrame frame;
  EliminationOptions options;
  std::vector<std::uint32_t> cells;        // surface vertex id -> cell index
  std::vector<Vertex> vertex;              // id -> point, height, grid position
  std::vector<Home> home;                  // id -> its link (see kInsideBit)
  std::vector<std::uint32_t> spill;        // the links too long for their home block
  std::vector<double> initial;             // importance from compute_importance()
  std::vector<std::uint32_t> evaluations;  // per-vertex counter, seeds Monte Carlo VP
  IndexedMinHeap heap;
  bool heap_ready = false;
  Delaunay predicates;  // empty: its perturbed in-circle test only
  std::size_t alive = 0;

  double inv[2][2];  // frame (u, w) -> grid (col, row)

  Impl(const HeightGrid& g, const GridFrame& f, const EliminationOptions& o)
      : grid(g), footprint(g), frame(f), options(o) {
    f.inverse(inv);
  }

  const Point& point(std::uint32_t id) const { return vertex[id].p; }

  Point3 metric(std::uint32_t id) const {
    const double s = frame.metres_per_unit;
    const Vertex& v = vertex[id];
    return {s * v.p.x(), s * v.p.y(), v.z};
  }

  bool label(std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
    if (a == kInfinite || b == kInfinite || c == kInfinite) return false;
    const std::int64_t sc = std::int64_t{vertex[a].col} + vertex[b].col + vertex[c].col;
    const std::int64_t sr = std::int64_t{vertex[a].row} + vertex[b].row + vertex[c].row;
    return footprint.contains_third(sc, sr);
  }

  // Whether p lies inside the circle through a, b, c (counter-clockwise), by CGAL's perturbed
  // test (a point on the circle is inside or not as a symbolic perturbation decides). First
  // the determinant in doubles with Shewchuk's a priori error bound ("Adaptive Precision
  // Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997: incircle's
  // errboundA), which settles nearly every test; where its sign is in doubt, exactly on the
  // frame's lattice (lattice_in_circle), else by CGAL's.
  bool in_circle(const Point& a, const Point& b, const Point& c, const Point& p) const {
    const double adx = a.x() - p.x(), ady = a.y() - p.y();
    const double bdx = b.x() - p.x(), bdy = b.y() - p.y();
    const double cdx = c.x() - p.x(), cdy = c.y() - p.y();
    const double bc = bdx * cdy - cdx * bdy, ca = cdx * ady - adx * cdy, ab = adx * bdy - bdx * ady;
    const double al = adx * adx + ady * ady, bl = bdx * bdx + bdy * bdy, cl = cdx * cdx + cdy * cdy;
    const double det = al * bc + bl * ca + cl * ab;
    const double permanent = (std::abs(bdx * cdy) + std::abs(cdx * bdy)) * al +
                             (std::abs(cdx * ady) + std::abs(adx * cdy)) * bl +
                             (std::abs(adx * bdy) + std::abs(bdx * ady)) * cl;
    constexpr double kEpsilon = 0x1p-53;
    constexpr double kBound = (10 + 96 * kEpsilon) * kEpsilon;
    if (det > kBound * permanent) return true;
    if (-det > kBound * permanent) return false;
    return in_circle_exact(a, b, c, p);
  }

  // in_circle's answer where the test in doubles leaves it in doubt. note: out of line, so
  // that in_circle itself stays small enough to be inlined into the refill's loop.
  [[gnu::noinline]] bool in_circle_exact(const Point& a, const Point& b, const Point& c,
                                         const Point& p) const {
    const int lattice = lattice_in_circle(a.x(), a.y(), b.x(), b.y(), c.x(), c.y(), p.x(), p.y());
    if (lattice >= 0) return lattice != 0;
    return predicates.side_of_oriented_circle(a, b, c, p, true) == CGAL::ON_POSITIVE_SIDE;
  }

  // Whether a -> b -> p turns left (counter-clockwise), by CGAL's exact orientation, asked
  // only where doubles leave the sign in doubt (orientation_filtered: a fifth of the refill's
  // mispredictions were CGAL's own filter's).
  static bool left_turn(const Point& a, const Point& b, const Point& p) {
    const int sign = orientation_filtered(a.x(), a.y(), b.x(), b.y(), p.x(), p.y());
    if (sign != 0) return sign > 0;
    return CGAL::orientation(a, b, p) == CGAL::LEFT_TURN;
  }

  // Delaunay refill of poly[lo..hi], closed by the edge poly[hi] -> poly[lo] with the
  // polygon on its left, into tris: counter-clockwise triangles, the first one on the closing
  // edge. Returns false on a degenerate (collinear) polygon.
  //
  // With s.memo, a polygon that is an exact translate of the last one refilled gets the same
  // triangles without a test: orientation and in-circle signs are the same for translated
  // points, and so is the perturbation's xy order (a full grid's first evaluations: nearly
  // every star is the same hexagon).
  bool refill(const std::vector<std::uint32_t>& poly, std::vector<LinkTriangle>& tris,
              Scratch& s) const {
    if (s.memo) {
      const Point& o = point(poly[0]);
      bool same = s.memo_valid && poly.size() == s.memo_offsets.size() + 1;
      for (std::size_t j = 1; same && j < poly.size(); ++j) {
        const Point& p = point(poly[j]);
        same = p.x() - o.x() == s.memo_offsets[j - 1].x() &&
               p.y() - o.y() == s.memo_offsets[j - 1].y() && exact_difference(p.x(), o.x()) &&
               exact_difference(p.y(), o.y());
      }
      if (same) {
        tris = s.memo_tris;
        return s.memo_ok;
      }
    }
    const bool ok = refill_anew(poly, tris, s);
    if (s.memo) {
      s.memo_offsets.clear();
      s.memo_valid = true;
      const Point& o = point(poly[0]);
      for (std::size_t j = 1; j < poly.size() && s.memo_valid; ++j) {
        const Point& p = point(poly[j]);
        s.memo_valid = exact_difference(p.x(), o.x()) && exact_difference(p.y(), o.y());
        s.memo_offsets.emplace_back(p.x() - o.x(), p.y() - o.y());
      }
      s.memo_tris = tris;
      s.memo_ok = ok;
    }
    return ok;
  }

  bool refill(Scratch& s) const { return refill(s.poly, s.tris, s); }

  bool refill_anew(const std::vector<std::uint32_t>& poly, std::vector<LinkTriangle>& tris,
                   Scratch& s) const {
    tris.clear();
    // note: the lower part of a split range, (lo, best), is taken on at once, not pushed and
    // popped: the ranges in the same order as a stack of them all gives. That stack's first
    // range, pushed as two 4-byte stores and read back as one 8-byte value, could not be
    // forwarded from the store buffer (perf: a fifth of refill's samples after that read).
    s.todo.clear();
    int lo = 0, hi = static_cast<int>(poly.size()) - 1;
    for (;;) {
      if (hi - lo < 2) {
        if (s.todo.empty()) break;
        lo = s.todo.back().first;
        hi = s.todo.back().second;
        s.todo.pop_back();
        continue;
      }
      const Point& a = point(poly[hi]);
      const Point& b = point(poly[lo]);
      int best = -1;
      for (int c = lo + 1; c < hi; ++c) {
        const Point& p = point(poly[c]);
        if (!left_turn(a, b, p)) continue;
        if (best < 0 || in_circle(a, b, point(poly[best]), p)) best = c;
      }
      if (best < 0) return false;
      // note: written in place, field by field: a pair or triangle built on the stack was read
      // back in 8 bytes over two 4-byte stores, which cannot be forwarded.
      LinkTriangle& t = tris.emplace_back();
      t[0] = hi, t[1] = lo, t[2] = best;
      auto& range = s.todo.emplace_back();
      range.first = best, range.second = hi;
      hi = best;
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
    const Point& pa = point(s.poly.front());
    const Point& pb = point(s.poly.back());
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
    for (std::size_t j = (first + s.poly.size()) % n; j != first; j = link_next(j, n)) {
      const std::uint32_t q = s.ring[j];
      if (q == s.poly.front() || q == s.poly.back() || q == kInfinite) continue;
      bound(point(q));
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
  // v -> ring[j] -> ring[j+1] is in the footprint.
  static std::uint32_t link_size(const Home& h) { return h.size & ~(kSpilled | kExactKey); }
  bool exact_key(std::uint32_t id) const { return (home[id].size & kExactKey) != 0; }
  void set_exact_key(std::uint32_t id, bool exact) {
    home[id].size = (home[id].size & ~kExactKey) | (exact ? kExactKey : 0);
  }
  const std::uint32_t* link(const Home& h) const {
    return h.size & kSpilled ? spill.data() + h.spill_at() : h.e;
  }
  std::uint32_t* link(Home& h) { return h.size & kSpilled ? spill.data() + h.spill_at() : h.e; }

  void read_ring(std::uint32_t v, Scratch& s) const {
    const Home& h = home[v];
    const std::uint32_t* e = link(h);
    const std::uint32_t size = link_size(h);
    s.ring.resize(size);
    s.inside.resize(size);
    for (std::uint32_t j = 0; j < size; ++j) {
      const std::uint32_t id = e[j] & kIdMask;
      s.ring[j] = id;
      s.inside[j] = (e[j] & kInsideBit) != 0;
      // note: the ring's points are read next (the refill's predicates, the star's heights),
      // each vertex's first touch a cache miss: asked for now, all of them at once.
      if (id != kInfinite) __builtin_prefetch(&vertex[id]);
    }
  }

  // Number of runs of inside faces round the ring (0 when all or none are inside), and the
  // first face of the last run.
  static std::size_t inside_runs(const Scratch& s, std::size_t& first) {
    const std::size_t n = s.ring.size();
    std::size_t runs = 0;
    for (std::size_t j = 0; j < n; ++j) {
      if (s.inside[j] && !s.inside[link_prev(j, n)]) ++runs, first = j;
    }
    return runs;
  }

  // The end of the inside run starting at `first`: the ring index after its last face.
  static std::size_t run_end(const Scratch& s, std::size_t first) {
    std::size_t j = first;
    while (s.inside[j]) j = link_next(j, s.ring.size());
    return j;
  }

  // v's removal for the log: on the outline, the ends of the inside run of faces round it.
  Removal removal(std::uint32_t v, Scratch& s) const {
    Removal r;
    r.cell = cells[v];
    read_ring(v, s);
    std::size_t first = 0;
    if (inside_runs(s, first) > 0) {
      r.outline = true;
      r.next = cells[s.ring[first]];
      r.prev = cells[s.ring[run_end(s, first)]];
    }
    return r;
  }

  // The polygon of a closed star (after read_ring): the whole link, from its least id, so
  // that the refill's triangles and the importance's sums come in an order fixed by the star.
  static void closed_polygon(Scratch& s) {
    const std::size_t n = s.ring.size();
    std::size_t least = 0;
    for (std::size_t j = 1; j < n; ++j) least = s.ring[j] < s.ring[least] ? j : least;
    s.poly.resize(n);
    for (std::size_t j = 0, i = least; j < n; ++j, i = link_next(i, n)) s.poly[j] = s.ring[i];
  }

  // The polygon of an outline vertex's inside run of faces (after read_ring; the run from
  // first): a, the link between, b.
  static void inside_polygon(Scratch& s, std::size_t first) {
    const std::size_t n = s.ring.size(), end = run_end(s, first);
    s.poly.clear();
    for (std::size_t j = first; j != end; j = link_next(j, n)) s.poly.push_back(s.ring[j]);
    s.poly.push_back(s.ring[end]);
  }

  // The outer side of an outline vertex's hole (after read_ring; the inside run from first):
  // the link from b round to a, into s.outer, and its refill into s.outer_tris (none on the
  // convex hull, where it is b, the infinite vertex, a). False where it cannot be refilled
  // (the vertex then stays).
  bool outer_refill(Scratch& s, std::size_t first) const {
    const std::size_t n = s.ring.size(), end = run_end(s, first);
    s.outer.clear();
    for (std::size_t j = end; j != first; j = link_next(j, n)) s.outer.push_back(s.ring[j]);
    s.outer.push_back(s.ring[first]);
    s.outer_tris.clear();
    if (std::find(s.outer.begin(), s.outer.end(), kInfinite) != s.outer.end()) {
      // On the hull with the outline straight through v, a and b are its hull neighbours.
      return s.outer.size() == 3;
    }
    return refill(s.outer, s.outer_tris, s);
  }

  // Importance of v, or kLocked when v must stay (a corner or bend of the outline, or an
  // outline vertex whose removal would change the footprint). With deferred given and exact
  // VP, gives vp_volume_bound (cheaper, no more than the importance) instead when that is
  // above defer_above, and says so in *deferred.
  double evaluate(std::uint32_t v, Scratch& s, double defer_above = 0, bool* deferred = nullptr) {
    if (deferred) *deferred = false;
    if (!options.pinned.empty() && options.pinned[cells[v]]) return kLocked;
    read_ring(v, s);
    const std::size_t n = s.ring.size();
    const std::size_t n_inside =
        static_cast<std::size_t>(std::count(s.inside.begin(), s.inside.end(), 1));
    if (n_inside == 0) return kLocked;

    bool closed = n_inside == n;
    std::size_t first = 0;  // first inside face of the (single) inside run
    if (closed) {
      closed_polygon(s);
    } else {
      if (inside_runs(s, first) != 1) return kLocked;  // the footprint pinches at v
      inside_polygon(s, first);
      // The outline runs a -> v -> b; it must be straight (in grid space) through v.
      const Vertex &a = vertex[s.poly.front()], &b = vertex[s.poly.back()], &c = vertex[v];
      const std::int64_t ax = a.col - c.col, ay = a.row - c.row;
      const std::int64_t bx = b.col - c.col, by = b.row - c.row;
      if (ax * by - ay * bx != 0 || ax * bx + ay * by >= 0) return kLocked;
      if (options.outline_chord_ok &&
          !options.outline_chord_ok(cells[s.poly.front()], cells[s.poly.back()])) {
        return kLocked;
      }
    }
    if (s.poly.size() < 3) return kLocked;

    const bool need_refill = options.importance == Importance::vp || !closed;
    if (need_refill && !refill(s)) return kLocked;
    if (!closed) {
      // The straight outline edge a-b must be Delaunay after the removal: no link vertex
      // beyond it may lie in the circle of its inner triangle.
      const Point& pa = point(s.poly.front());
      const Point& pb = point(s.poly.back());
      const Point& pr = point(s.poly[s.tris.front()[2]]);
      for (std::size_t j = (first + s.poly.size()) % n; j != first; j = link_next(j, n)) {
        const std::uint32_t q = s.ring[j];
        if (q == s.poly.front() || q == s.poly.back() || q == kInfinite) continue;
        if (in_circle(pb, pa, pr, point(q))) return kLocked;
      }
      if (options.chord_box && !witness_in_box(s, first, pr)) return kLocked;
      if (!outer_refill(s, first)) return kLocked;
    }

    s.pts.clear();
    for (const std::uint32_t p : s.poly) s.pts.push_back(metric(p));
    const Star star{metric(v), s.pts.data(), s.pts.size(), closed};
    if (options.importance == Importance::pld) return pld_importance(star);
    if (options.vp_volume == VolumeMethod::monte_carlo) {
      return vp_volume_monte_carlo(star, s.tris, options.vp_samples,
                                   mix_seed(options.seed, cells[v], evaluations[v]++));
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

  // A refill's triangles (tris over poly) appended to s.faces, labelled.
  void add_faces(const std::vector<std::uint32_t>& poly, const std::vector<LinkTriangle>& tris,
                 Scratch& s) const {
    for (const LinkTriangle& t : tris) {
      const std::uint32_t a = poly[t[0]], b = poly[t[1]], c = poly[t[2]];
      s.faces.push_back({{a, b, c}, label(a, b, c)});
    }
  }

  // Removes v (its importance finite, so its removal keeps the footprint): the hole is
  // refilled as CGAL's remove() would, and each link vertex's link has v replaced by its new
  // neighbours. On the outline, the new outline edge a-b is Delaunay (evaluate() checked), so
  // the hole splits along it into the inside run's polygon and the outer one (on the convex
  // hull, a single face with the infinite vertex).
  void remove(std::uint32_t v, Scratch& s) {
    read_ring(v, s);
    const std::size_t n = s.ring.size();
    // note: each link vertex's home block is written below, after the refill: asked for now
    // (perf: its first load was 8 % of vp's samples).
    for (const std::uint32_t u : s.ring) {
      if (u != kInfinite) __builtin_prefetch(&home[u], 1);
    }
    s.faces.clear();
    std::size_t first = 0;
    if (inside_runs(s, first) == 0) {
      closed_polygon(s);
      if (!refill(s)) throw std::logic_error("elimination: a removed vertex's hole is degenerate");
      add_faces(s.poly, s.tris, s);
    } else {
      inside_polygon(s, first);
      if (!refill(s) || !outer_refill(s, first)) {
        throw std::logic_error("elimination: a removed vertex's hole is degenerate");
      }
      add_faces(s.poly, s.tris, s);
      if (s.outer_tris.empty()) {  // on the hull: b, the infinite vertex, a
        s.faces.push_back({{s.outer[0], s.outer[1], s.outer[2]}, false});
      } else {
        add_faces(s.outer, s.outer_tris, s);
      }
    }
    for (std::size_t j = 0; j < n; ++j) {
      if (s.ring[j] != kInfinite) splice(s.ring[j], v, s);
    }
    home[v] = Home();
    --alive;
  }

  // Vertex id's link, counter-clockwise (entries as in Home), stored.
  void set_link(std::uint32_t id, const std::uint32_t* ring, std::size_t size) {
    Home& h = home[id];
    h.size = static_cast<std::uint32_t>(size) | kExactKey;
    std::copy_n(ring, size,
                size <= kHomeLinks ? h.e : to_spill(h, static_cast<std::uint32_t>(size + 4)));
  }

  // Room for `room` entries at the spill pool's end made h's (its size word keeps its count
  // and kExactKey, gains kSpilled); returns where. The home block's entries are overwritten:
  // copy them out first.
  std::uint32_t* to_spill(Home& h, std::uint32_t room) {
    const std::uint64_t at = spill.size();
    spill.resize(at + room);
    h.size |= kSpilled;
    h.e[0] = static_cast<std::uint32_t>(at);
    h.e[1] = static_cast<std::uint32_t>(at >> 32);
    h.e[2] = room;
    return spill.data() + at;
  }

  // The links of the Delaunay triangulation of the vertices, by CGAL's insertion.
  void cgal_links(const Progress& progress) {
    const std::size_t n = vertex.size();
    // The links, side by side as CGAL gives them, then CGAL's triangulation freed, then the
    // home blocks: its memory and theirs are never held at once (peak -9 % on kilauea).
    std::vector<std::uint64_t> start(n + 1, 0);
    std::vector<std::uint32_t> links;
    links.reserve(7 * n);
    {
      // CGAL's range insertion with info (Delaunay_triangulation_2::insert_with_info), written
      // out so that progress can stop it: the same spatial sort and hinted insertions.
      Delaunay dt;
      std::vector<VertexHandle> handle(n);
      {
        std::vector<Point> points(n);
        for (std::size_t i = 0; i < n; ++i) points[i] = vertex[i].p;
        std::vector<std::size_t> order(n);
        for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
        using Traits =
            CGAL::Spatial_sort_traits_adapter_2<K, CGAL::Pointer_property_map<Point>::type>;
        CGAL::spatial_sort(order.begin(), order.end(),
                           Traits(CGAL::make_property_map(points), dt.geom_traits()));
        Delaunay::Face_handle hint;
        for (std::size_t k = 0; k < order.size(); ++k) {
          if (k % 65536 == 65535 && progress &&
              !progress(static_cast<double>(k) / static_cast<double>(order.size()),
                        "triangulate")) {
            throw Cancelled();
          }
          const VertexHandle v = dt.insert(points[order[k]], hint);
          if (v != VertexHandle()) {
            v->info() = static_cast<std::uint32_t>(order[k]);
            hint = v->face();
          }
        }
      }
      if (dt.dimension() < 2) throw std::invalid_argument("all valid cells are collinear");
      for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) {
        handle[v->info()] = v;
      }
      for (std::uint32_t id = 0; id < n; ++id) {
        start[id] = links.size();
        const VertexHandle v = handle[id];
        if (v == VertexHandle()) continue;  // a duplicate point (not inserted)
        auto fc = dt.incident_faces(v);
        const auto done = fc;
        do {
          const int i = fc->index(v);
          const VertexHandle a = fc->vertex(Delaunay::ccw(i)), b = fc->vertex(Delaunay::cw(i));
          const std::uint32_t ia = dt.is_infinite(a) ? kInfinite : a->info();
          const std::uint32_t ib = dt.is_infinite(b) ? kInfinite : b->info();
          links.push_back(ia | (label(id, ia, ib) ? kInsideBit : 0));
        } while (++fc != done);
      }
    }
    start[n] = links.size();
    home.resize(n);
    for (std::uint32_t id = 0; id < n; ++id) {
      if (start[id + 1] > start[id])
        set_link(id, links.data() + start[id], start[id + 1] - start[id]);
    }
  }

  // The links of the Delaunay triangulation of a DEM whose every cell is a vertex (ids in
  // row-major order), straight from the grid: no vertex lies in a square's circle but its
  // corners, so each square is split along the diagonal that CGAL's perturbed in-circle test
  // picks, and the convex hull is the grid's border. The perturbed Delaunay triangulation is
  // unique, so this is the triangulation cgal_links() makes, in a tenth of the time. False
  // (nothing made) where the frame's shear makes the grid's squares not Delaunay.
  bool grid_links(const Progress& progress) {
    const int w = grid.width, h = grid.height;
    auto at = [w](int c, int r) { return static_cast<std::uint32_t>(r) * w + c; };
    // main[square]: square (c, r) (corners c..c+1, r..r+1) split along (c, r) - (c+1, r+1).
    std::vector<char> main((static_cast<std::size_t>(w) - 1) * (h - 1));
    for (int r = 0; r + 1 < h; ++r) {
      for (int c = 0; c + 1 < w; ++c) {
        const Point &p00 = point(at(c, r)), &p10 = point(at(c + 1, r));
        const Point &p01 = point(at(c, r + 1)), &p11 = point(at(c + 1, r + 1));
        const bool ccw = left_turn(p00, p10, p11);
        const bool inside = ccw ? in_circle(p00, p10, p11, p01) : in_circle(p00, p11, p10, p01);
        main[static_cast<std::size_t>(r) * (w - 1) + c] = inside ? 0 : 1;
      }
    }
    // The grid's own edges must be Delaunay too (a frame sheared past the lattice's reduced
    // basis makes its Delaunay edges cross squares): each against the far corner of the
    // triangle beyond it. Else false, and nothing is made.
    auto encircles = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t t) {
      const bool ccw = left_turn(point(a), point(b), point(c));
      return ccw ? in_circle(point(a), point(b), point(c), point(t))
                 : in_circle(point(a), point(c), point(b), point(t));
    };
    auto is_main = [&](int c, int r) {
      return main[static_cast<std::size_t>(r) * (w - 1) + c] != 0;
    };
    for (int r = 1; r + 1 < h; ++r) {  // edge (c, r) - (c+1, r), squares (c, r-1) and (c, r)
      for (int c = 0; c + 1 < w; ++c) {
        const std::uint32_t below = is_main(c, r) ? at(c + 1, r + 1) : at(c, r + 1);
        const std::uint32_t above = is_main(c, r - 1) ? at(c, r - 1) : at(c + 1, r - 1);
        if (encircles(at(c, r), at(c + 1, r), below, above)) return false;
      }
    }
    for (int r = 0; r + 1 < h; ++r) {  // edge (c, r) - (c, r+1), squares (c-1, r) and (c, r)
      for (int c = 1; c + 1 < w; ++c) {
        const std::uint32_t right = is_main(c, r) ? at(c + 1, r + 1) : at(c + 1, r);
        const std::uint32_t left = is_main(c - 1, r) ? at(c - 1, r) : at(c - 1, r + 1);
        if (encircles(at(c, r), at(c, r + 1), right, left)) return false;
      }
    }
    auto square = [&](int c, int r) { return c >= 0 && r >= 0 && c + 1 < w && r + 1 < h; };
    auto split_main = [&](int c, int r) { return square(c, r) && is_main(c, r); };
    auto split_anti = [&](int c, int r) { return square(c, r) && !is_main(c, r); };
    // The eight directions by angle in (col, row); the frame keeps that turn or reverses it.
    static constexpr int kDc[8] = {1, 1, 0, -1, -1, -1, 0, 1};
    static constexpr int kDr[8] = {0, 1, 1, 1, 0, -1, -1, -1};
    const bool reverse = frame.m[0][0] * frame.m[1][1] - frame.m[0][1] * frame.m[1][0] < 0;
    home.resize(vertex.size());
    std::vector<std::uint32_t> ring;
    for (int r = 0; r < h; ++r) {
      if (progress && r % std::max(1, 65536 / w) == 0 && r > 0 &&
          !progress(static_cast<double>(r) / h, "triangulate")) {
        throw Cancelled();
      }
      for (int c = 0; c < w; ++c) {
        bool outside[8], present[8];
        for (int k = 0; k < 8; ++k) {
          const int nc = c + kDc[k], nr = r + kDr[k];
          outside[k] = nc < 0 || nr < 0 || nc >= w || nr >= h;
          present[k] = !outside[k];
        }
        if (present[1]) present[1] = split_main(c, r);
        if (present[3]) present[3] = split_anti(c - 1, r);
        if (present[5]) present[5] = split_main(c - 1, r - 1);
        if (present[7]) present[7] = split_anti(c, r - 1);
        // From the end of the outside arc (on the border), the infinite vertex last.
        int start = 0;
        bool border = false;
        for (int k = 0; k < 8; ++k) {
          if (outside[k] && !outside[(k + 1) % 8]) start = (k + 1) % 8, border = true;
        }
        ring.clear();
        for (int j = 0; j < 8; ++j) {
          const int k = (start + j) % 8;
          if (present[k]) ring.push_back(at(c + kDc[k], r + kDr[k]));
        }
        if (border) ring.push_back(kInfinite);
        if (reverse) std::reverse(ring.begin(), ring.end());
        const std::uint32_t id = at(c, r);
        const std::size_t n = ring.size();
        for (std::size_t j = 0; j < n; ++j) {
          if (label(id, ring[j] & kIdMask, ring[(j + 1) % n] & kIdMask)) ring[j] |= kInsideBit;
        }
        set_link(id, ring.data(), ring.size());
      }
    }
    return true;
  }

  // In u's link, v replaced by u's neighbours among the new faces: u's link reads ..., c, v,
  // d, ... and now reads c, (the new ones), d, the faces between them the new faces round u.
  void splice(std::uint32_t u, std::uint32_t v, Scratch& s) {
    Home& h = home[u];
    std::uint32_t* e = link(h);
    const std::uint32_t n = link_size(h);
    std::uint32_t p = 0;
    while ((e[p] & kIdMask) != v) ++p;
    const std::uint32_t before = (p + n - 1) % n;
    const std::uint32_t d = e[(p + 1) % n] & kIdMask;
    // Round u from c: each new face u -> c -> next gives c's flag and the next neighbour.
    std::uint32_t c = e[before] & kIdMask;
    s.splice.clear();
    for (;;) {
      const NewFace* f = nullptr;
      int k = 0;
      for (const NewFace& g : s.faces) {
        for (k = 0; k < 3 && !(g.v[k] == u && g.v[(k + 1) % 3] == c); ++k) {
        }
        if (k < 3) {
          f = &g;
          break;
        }
      }
      if (!f || s.splice.size() > s.faces.size()) {
        throw std::logic_error("elimination: a hole's faces do not close round its link");
      }
      const std::uint32_t flag = f->inside ? kInsideBit : 0;
      if (s.splice.empty()) {
        e[before] = c | flag;
      } else {
        s.splice.back() = c | flag;
      }
      const std::uint32_t next = f->v[(k + 2) % 3];
      if (next == d) break;
      s.splice.push_back(next);
      c = next;
    }
    // v's entry becomes the new stretch.
    const std::uint32_t size = n - 1 + static_cast<std::uint32_t>(s.splice.size());
    const std::uint32_t capacity = h.size & kSpilled ? h.spill_capacity() : kHomeLinks;
    if (size > capacity) {
      // note: the entries copied out first (to_spill overwrites a home block's, and moves the
      // pool, a spilled link's).
      s.moved.assign(e, e + n);
      e = to_spill(h, std::max(2 * capacity, size + 4));
      std::copy(s.moved.begin(), s.moved.end(), e);
    }
    std::memmove(e + p + s.splice.size(), e + p + 1, (n - p - 1) * sizeof *e);
    std::copy(s.splice.begin(), s.splice.end(), e + p);
    h.size = size | (h.size & (kSpilled | kExactKey));
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
  if (m.cells.size() >= kInfinite) {
    throw std::invalid_argument("more than 2^31 - 2 valid cells: too many for vp and pld");
  }
  const std::size_t n = m.cells.size();
  m.vertex.resize(n);
  for (std::uint32_t id = 0; id < n; ++id) {
    Vertex& v = m.vertex[id];
    v.col = static_cast<std::int32_t>(m.cells[id] % grid.width);
    v.row = static_cast<std::int32_t>(m.cells[id] / grid.width);
    v.z = grid.z[m.cells[id]];
    v.p = Point(frame.u(v.col, v.row), frame.w(v.col, v.row));
  }
  if (options.grid_triangulation && n == static_cast<std::size_t>(grid.width) * grid.height &&
      grid.width >= 2 && grid.height >= 2) {
    if (!m.grid_links(progress)) m.cgal_links(progress);
  } else {
    m.cgal_links(progress);
  }
  m.alive = 0;
  for (std::uint32_t id = 0; id < n; ++id) m.alive += m.home[id].size > 0 ? 1 : 0;
  m.initial.assign(n, kLocked);
  m.evaluations.assign(n, 0);
  m.heap = IndexedMinHeap(n);
}

Eliminator::~Eliminator() = default;

std::size_t Eliminator::vertex_count() const { return impl_->cells.size(); }
std::size_t Eliminator::alive_count() const { return impl_->alive; }

void Eliminator::compute_importance(std::size_t begin, std::size_t end) {
  Scratch scratch;
  scratch.memo = true;
  // A lower bound now, the importance when needed (see eliminate()).
  bool deferred = false;
  bool* const defer = impl_->lazy() ? &deferred : nullptr;
  for (std::size_t id = begin; id < end; ++id) {
    if (impl_->home[id].size == 0) continue;
    impl_->initial[id] = impl_->evaluate(static_cast<std::uint32_t>(id), scratch, -1.0, defer);
    impl_->set_exact_key(static_cast<std::uint32_t>(id), !deferred);
  }
}

void Eliminator::eliminate(std::size_t keep, const Progress& progress, std::vector<Removal>* log) {
  Impl& m = *impl_;
  if (!m.heap_ready) {
    m.heap_ready = true;
    std::vector<std::uint32_t> ids;
    std::vector<double> keys;
    for (std::uint32_t id = 0; id < m.cells.size(); ++id) {
      if (m.home[id].size > 0 && m.initial[id] != kLocked) {
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
  std::vector<std::uint32_t> link;
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
    if (!m.exact_key(top)) {
      m.set_exact_key(top, true);
      const double importance = m.evaluate(top, scratch);
      assert(importance != kLocked && importance >= m.heap.top_key());
      m.heap.set(top, importance);
      continue;
    }
    const std::uint32_t id = m.heap.pop();  // top
    if (log) log->push_back(m.removal(id, scratch));
    m.remove(id, scratch);
    link.clear();
    for (const std::uint32_t u : scratch.ring) {
      if (u == kInfinite) continue;
      link.push_back(u);
      m.heap.prefetch_slot(u);
    }
    // note: the heap (San Gabriel: 770k entries, 12 MB) is mostly out of the caches, and its
    // slot and entry of each link vertex were the eliminator's most stalled loads: asked for
    // ahead, while the vertex's importance is computed.
    for (const std::uint32_t u : link) {
      m.heap.prefetch(u);
      // A bound no higher than the top's key would come up next: its importance is computed
      // now, while the star is at hand (fewer cycles than deferring it, or deferring those up
      // to twice the top's key, by cachegrind's count).
      const double importance =
          m.evaluate(u, scratch, m.heap.empty() ? 0.0 : m.heap.top_key(), defer);
      m.set_exact_key(u, !deferred);
      if (importance == kLocked) {
        m.heap.erase(u);
      } else {
        m.heap.set(u, importance);
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
    if (m.home[id].size == 0) continue;
    out_index[id] = static_cast<std::uint32_t>(tin.cells.size());
    tin.cells.push_back(m.cells[id]);  // ids ascend with cells, so cells stay sorted
  }
  // Each inside face once, from its least corner (the faces' corners are finite).
  for (std::uint32_t id = 0; id < m.cells.size(); ++id) {
    const std::uint32_t* e = m.link(m.home[id]);
    const std::uint32_t size = Impl::link_size(m.home[id]);
    for (std::uint32_t j = 0; j < size; ++j) {
      if (!(e[j] & kInsideBit)) continue;
      const std::uint32_t a = e[j] & kIdMask, b = e[(j + 1) % size] & kIdMask;
      if (a < id || b < id) continue;
      tin.faces.push_back({out_index[id], out_index[a], out_index[b]});
    }
  }
  std::sort(tin.faces.begin(), tin.faces.end());
  return tin;
}

const std::vector<std::uint32_t>& Eliminator::cells() const { return impl_->cells; }
bool Eliminator::alive(std::size_t id) const { return impl_->home[id].size > 0; }

std::vector<OutlineEdge> Eliminator::outline_edges() const {
  const Impl& m = *impl_;
  std::vector<OutlineEdge> out;
  // An inside face id -> a -> b whose neighbour across id -> a (the face before it round id)
  // is not inside: the edge id -> a, the inside on its left.
  for (std::uint32_t id = 0; id < m.cells.size(); ++id) {
    const std::uint32_t* e = m.link(m.home[id]);
    const std::uint32_t size = Impl::link_size(m.home[id]);
    for (std::uint32_t j = 0; j < size; ++j) {
      if ((e[j] & kInsideBit) && !(e[(j + size - 1) % size] & kInsideBit)) {
        out.push_back({m.cells[id], m.cells[e[j] & kIdMask]});
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace dpts::core

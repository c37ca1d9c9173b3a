// dpts's quadric edge collapse (see qem.hpp).
//
// Sources: Garland and Heckbert, "Surface simplification using quadric error metrics",
// SIGGRAPH 1997 (greedy collapse by quadric cost, optimal placement, the segment fallback);
// the triangle quadric (a plane quadric weighted by the triangle's squared doubled area) as in
// CGAL's GarlandHeckbert_triangle_policies (Trettner and Kobbelt, Eurographics 2020).
#include "core/qem.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>

#include "core/errors.hpp"
#include "core/indexed_heap.hpp"
#include "core/predicates.hpp"

namespace dpts::core {

Quadric Quadric::plane(const double n[3], double d) {
  Quadric q;
  q.a00 = n[0] * n[0];
  q.a01 = n[0] * n[1];
  q.a02 = n[0] * n[2];
  q.a11 = n[1] * n[1];
  q.a12 = n[1] * n[2];
  q.a22 = n[2] * n[2];
  q.b0 = n[0] * d;
  q.b1 = n[1] * d;
  q.b2 = n[2] * d;
  q.c = d * d;
  return q;
}

Quadric& Quadric::operator*=(double w) {
  a00 *= w, a01 *= w, a02 *= w, a11 *= w, a12 *= w, a22 *= w;
  b0 *= w, b1 *= w, b2 *= w, c *= w;
  return *this;
}

Quadric& Quadric::operator+=(const Quadric& q) {
  a00 += q.a00, a01 += q.a01, a02 += q.a02, a11 += q.a11, a12 += q.a12, a22 += q.a22;
  b0 += q.b0, b1 += q.b1, b2 += q.b2, c += q.c;
  return *this;
}

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
constexpr std::uint32_t kNone = 0xFFFFFFFFu;

// note: "x divisible by 3" as x times 3's inverse modulo 2^32 (0xAAAAAAAB) at most
// (2^32 - 1) / 3, for any 32-bit x: one multiply and a compare, not h % 3's multiply, shift and
// subtract (these two run on every step of every star walk).
inline bool multiple_of_3(std::uint32_t x) { return x * 0xAAAAAAABu <= 0x55555555u; }
inline std::uint32_t next_of(std::uint32_t h) { return multiple_of_3(h + 1) ? h - 2 : h + 1; }
inline std::uint32_t prev_of(std::uint32_t h) { return multiple_of_3(h) ? h + 2 : h - 1; }

// Exact orientation of (p, q, r) seen from above: > 0 counter-clockwise. CGAL's exact test
// only where doubles leave the sign in doubt (orientation_filtered: CGAL's own filter was 5 %
// of qem's mispredictions).
inline CGAL::Orientation orient(const double* p, const double* q, const double* r) {
  const int sign = orientation_filtered(p[0], p[1], q[0], q[1], r[0], r[1]);
  if (sign != 0) return sign > 0 ? CGAL::LEFT_TURN : CGAL::RIGHT_TURN;
  return CGAL::orientation(K::Point_2(p[0], p[1]), K::Point_2(q[0], q[1]), K::Point_2(r[0], r[1]));
}

inline double area3(const double* a, const double* b, const double* c) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double n0 = u[1] * v[2] - u[2] * v[1], n1 = u[2] * v[0] - u[0] * v[2],
               n2 = u[0] * v[1] - u[1] * v[0];
  return 0.5 * std::sqrt(n0 * n0 + n1 * n1 + n2 * n2);
}

// area3(a, b, c) and area3(d, e, f) at once: the same operations, in two lanes (the same bits).
inline void area3_pair(const double* a, const double* b, const double* c, const double* d,
                       const double* e, const double* f, double& first, double& second) {
#if defined(__SSE2__)
  auto lanes = [](double x, double y) { return _mm_set_pd(y, x); };  // x in lane 0
  auto diff = [&](const double* p, const double* q, const double* r, const double* s, int k) {
    return _mm_sub_pd(lanes(p[k], r[k]), lanes(q[k], s[k]));  // p - q, r - s
  };
  const __m128d u0 = diff(b, a, e, d, 0), u1 = diff(b, a, e, d, 1), u2 = diff(b, a, e, d, 2);
  const __m128d v0 = diff(c, a, f, d, 0), v1 = diff(c, a, f, d, 1), v2 = diff(c, a, f, d, 2);
  const __m128d n0 = _mm_sub_pd(_mm_mul_pd(u1, v2), _mm_mul_pd(u2, v1));
  const __m128d n1 = _mm_sub_pd(_mm_mul_pd(u2, v0), _mm_mul_pd(u0, v2));
  const __m128d n2 = _mm_sub_pd(_mm_mul_pd(u0, v1), _mm_mul_pd(u1, v0));
  const __m128d sq =
      _mm_add_pd(_mm_add_pd(_mm_mul_pd(n0, n0), _mm_mul_pd(n1, n1)), _mm_mul_pd(n2, n2));
  const __m128d r = _mm_mul_pd(_mm_set1_pd(0.5), _mm_sqrt_pd(sq));
  first = _mm_cvtsd_f64(r);
  second = _mm_cvtsd_f64(_mm_unpackhi_pd(r, r));
#else
  first = area3(a, b, c);
  second = area3(d, e, f);
#endif
}

// x + y, built in place (the same sums as +=).
inline Quadric sum(const Quadric& x, const Quadric& y) {
  Quadric s;
  s.a00 = x.a00 + y.a00, s.a01 = x.a01 + y.a01, s.a02 = x.a02 + y.a02;
  s.a11 = x.a11 + y.a11, s.a12 = x.a12 + y.a12, s.a22 = x.a22 + y.a22;
  s.b0 = x.b0 + y.b0, s.b1 = x.b1 + y.b1, s.b2 = x.b2 + y.b2, s.c = x.c + y.c;
  return s;
}

// The point minimising q: its optimum when A is well conditioned, else the best point of the
// segment p0-p1 (Garland and Heckbert's fallback, as CGAL's construct_optimal_point_singular).
void optimum(const Quadric& q, const double* p0, const double* p1, double* x) {
  // Cofactors of A.
  const double c00 = q.a11 * q.a22 - q.a12 * q.a12, c01 = q.a02 * q.a12 - q.a01 * q.a22,
               c02 = q.a01 * q.a12 - q.a02 * q.a11;
  const double det = q.a00 * c00 + q.a01 * c01 + q.a02 * c02;
  const double scale = std::max({std::fabs(q.a00), std::fabs(q.a11), std::fabs(q.a22)});
  if (std::fabs(det) > 1e-12 * scale * scale * scale && std::isfinite(det)) {
    const double c11 = q.a00 * q.a22 - q.a02 * q.a02, c12 = q.a01 * q.a02 - q.a00 * q.a12,
                 c22 = q.a00 * q.a11 - q.a01 * q.a01;
    // x = -A^-1 b.
    x[0] = -(c00 * q.b0 + c01 * q.b1 + c02 * q.b2) / det;
    x[1] = -(c01 * q.b0 + c11 * q.b1 + c12 * q.b2) / det;
    x[2] = -(c02 * q.b0 + c12 * q.b1 + c22 * q.b2) / det;
    return;
  }
  const double d[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
  const double ad[3] = {q.a00 * d[0] + q.a01 * d[1] + q.a02 * d[2],
                        q.a01 * d[0] + q.a11 * d[1] + q.a12 * d[2],
                        q.a02 * d[0] + q.a12 * d[1] + q.a22 * d[2]};
  const double a = d[0] * ad[0] + d[1] * ad[1] + d[2] * ad[2];
  const double b =
      2 * (p0[0] * ad[0] + p0[1] * ad[1] + p0[2] * ad[2] + q.b0 * d[0] + q.b1 * d[1] + q.b2 * d[2]);
  double t;
  if (a == 0) {
    t = b < 0 ? 1.0 : b == 0 ? 0.5 : 0.0;
  } else {
    t = -b / (2 * a);
    if (t < 0 || t > 1 || a < 0) t = q(p0) > q(p1) ? 1.0 : 0.0;
  }
  for (int k = 0; k < 3; ++k) x[k] = p0[k] + t * d[k];
}

class Collapser {
 public:
  // Takes the mesh's coordinates and the options' quadrics.
  // progress is asked (at 0, "simplify") between the steps and every few thousand faces: on
  // a large mesh (QSlim's, a whole DEM) they take seconds before the first collapse, and a
  // stop asked for meanwhile must be honoured (Cancelled).
  Collapser(TriMesh&& mesh, QemOptions& options, const Progress& progress)
      : o_(&options), progress_(&progress) {
    const std::size_t n = mesh.vertex_count();
    const std::size_t f = mesh.faces.size();
    if (n >= kNone || 3 * f >= kNone) throw std::invalid_argument("qem: mesh too large");
    xyz_ = std::move(mesh.xyz);
    fv_.resize(3 * f);
    for (std::size_t i = 0; i < f; ++i) {
      for (int k = 0; k < 3; ++k) {
        if (mesh.faces[i][k] >= n) throw std::invalid_argument("qem: face index out of range");
        fv_[3 * i + k] = mesh.faces[i][k];
      }
    }
    mesh.faces = {};
    plane_ = std::move(o_->plane_xy);
    if (!plane_.empty() && (plane_.size() != 2 * n || !o_->to_plane)) {
      throw std::invalid_argument("qem: plane_xy needs 2 values per vertex and to_plane");
    }
    check();
    if (o_->opposites.empty()) {
      link_opposites();
    } else {
      adopt_opposites();
    }
    check();
    out_.assign(n, kNone);
    for (std::uint32_t h = 0; h < fv_.size(); ++h) {
      if (out_[fv_[h]] == kNone || opp_[h] == kNone) out_[fv_[h]] = h;
    }
    // Pinched: more than one outline edge leaves the vertex (two fans meet there).
    flags_.assign(n, 0);
    std::vector<std::uint8_t> border_out(n, 0);
    for (std::uint32_t h = 0; h < fv_.size(); ++h) {
      if (opp_[h] != kNone) continue;
      if (border_out[fv_[h]]++) flags_[fv_[h]] |= kPinched;
    }
    for (std::size_t v = 0; v < n; ++v) {
      if (out_[v] == kNone) flags_[v] |= kGone;  // not a corner of any face
      if (!o_->locked.empty() && o_->locked[v]) flags_[v] |= kLocked;
      if (!o_->frozen.empty() && o_->frozen[v]) flags_[v] |= kFrozen;
      if (out_[v] != kNone && opp_[out_[v]] == kNone) flags_[v] |= kBorder;
    }
    check();
    init_quadrics();
    check();
    // note: after the quadrics, which give no outline quadric between two locked vertices.
    if (o_->lock_outline) {
      for (std::size_t v = 0; v < n; ++v) {
        if (flags_[v] & kBorder) flags_[v] |= kLocked;
      }
    }
    alive_ = 0;
    for (std::size_t v = 0; v < n; ++v) alive_ += (flags_[v] & kGone) ? 0 : 1;
  }

  std::size_t alive() const { return alive_; }

  // A copy's options and progress: those of the QemCollapse holding it.
  void rebind(QemOptions& options, const Progress& progress) {
    o_ = &options;
    progress_ = &progress;
  }

  // Every edge's first cost queued (run()'s first step; prepare() may be called before).
  // keep: the count run() will collapse to (0: not known; prepare_full_costs needs it).
  void prepare(std::size_t keep = 0) {
    if (prepared_) return;
    prepared_ = true;
    heap_ = IndexedMinHeap(fv_.size());
    // note: with o_->for_ranges, each edge's first cost on its own, maybe on several threads,
    // then queued in edge order: the same queue as in order on this thread.
    // Edge h's first cost into cost; false if it has none (not queued).
    // note: the quadric's cost alone, a lower bound, as update() queues: an edge's full cost
    // is walked for when it comes up, and most edges are re-costed by a collapse nearby
    // before they do. st_helens_full to 10 %: 10 % fewer cycles (cachegrind estimate); the
    // default measure (60 points x 3 sets) on st_helens_crater, zion_canyon and
    // peru_mongon at 10, 30, 50 and 70 % (and 4 more DEMs at 10 and 50 %) moved by -3.9 %
    // to +6.0 % (mean +0.1 %).
    auto first_cost = [&](std::uint32_t h, double& cost) {
      Plan p;
      if (!first_edge(h) || !plan(h, p, false)) return false;
      cost = p.cost;
      return true;
    };
    if (o_->for_ranges) {
      std::vector<double> first(fv_.size());
      std::vector<char> planned(fv_.size(), 0);
      o_->for_ranges(fv_.size(), [&](std::size_t begin, std::size_t end) {
        for (auto h = static_cast<std::uint32_t>(begin); h < end; ++h) {
          planned[h] = first_cost(h, first[h]);
        }
      });
      for (std::uint32_t h = 0; h < fv_.size(); ++h) {
        if (planned[h]) heap_.push_unordered(h, first[h]);
      }
      if (o_->full_first_costs > 0 && keep > 0 && keep < alive_ && o_->area_weight != 0) {
        prepare_full_costs(first, planned, o_->full_first_costs * (alive_ - keep));
      }
    } else {
      // note: an edge's first half-edges listed a block at a time without a branch, then
      // planned: the test per half-edge (half of them pass, in no pattern) missed often.
      constexpr std::uint32_t kBlock = 1024;
      std::uint32_t firsts[kBlock];
      const auto n = static_cast<std::uint32_t>(fv_.size());
      for (std::uint32_t h0 = 0; h0 < n; h0 += kBlock) {
        const std::uint32_t h1 = std::min(n - h0, kBlock) + h0;
        std::uint32_t m = 0;
        for (std::uint32_t h = h0; h < h1; ++h) {
          firsts[m] = h;
          m += first_edge(h) ? 1 : 0;
        }
        for (std::uint32_t i = 0; i < m; ++i) {
          double cost;
          if (first_cost(firsts[i], cost)) heap_.push_unordered(firsts[i], cost);
        }
        if ((h1 & 0xFFFF) == 0) check();
      }
    }
    heap_.heapify();
    full_at_.assign(fv_.size(), kNone);
    stamp_.assign(xyz_.size() / 3, 0);
    mark_.assign(xyz_.size() / 3, 0);
  }

  // The full costs (o_->full_first_costs) of the interior edges of the m least first costs.
  // note: the piece engine's merge (collapsing about a fifth of its vertices) pops most edges
  // near the bottom of the queue once at their first cost, walks both ends' stars for the
  // area term, and mostly queues them again: San Gabriel to 10 %, 51.8k of its 59.5k pops,
  // 35.6k of its 40.3k requeues, all in qem's serial part. 20.2k of those pops found neither
  // end's star changed since the first costs; they lie among the 3 x collapses least first
  // costs (2 x: 15.9k of them). Made here on the threads, run() takes each as the cost it
  // would have walked for, to the bit (nothing it reads has changed), so the collapses and
  // the output are the same: the loop 0.187 -> 0.129 s, prepare 0.024 -> 0.055 s at 2 threads
  // (medians of 6 alternated runs).
  // note: at most kMaxFullFirstCosts (3 MB of ids and costs): a merge of a large DEM's group
  // (olympic_srtm1 to 10 %, about 400k collapses) would otherwise hold about 10 MB more at its
  // peak, for the first part of its collapses only.
  static constexpr std::size_t kMaxFullFirstCosts = std::size_t{1} << 18;
  void prepare_full_costs(const std::vector<double>& first, const std::vector<char>& planned,
                          std::size_t m) {
    // The edges that may be made: queued, interior (an outline edge is planned in full anyway).
    auto candidate = [&](std::uint32_t h) { return planned[h] && opp_[h] != kNone; };
    // The bound: the m-th least first cost of a candidate, as every 4th of them sees it (any
    // bound gives the same collapses).
    std::vector<float> sample;
    std::size_t candidates = 0;
    for (std::uint32_t h = 0; h < fv_.size(); ++h) {
      if (candidate(h) && candidates++ % 4 == 0) sample.push_back(static_cast<float>(first[h]));
    }
    m = std::min(m, kMaxFullFirstCosts);
    const std::size_t k = std::min(m / 4, sample.size());
    if (k == 0) return;
    std::nth_element(sample.begin(), sample.begin() + static_cast<std::ptrdiff_t>(k - 1),
                     sample.end());
    const double bound = sample[k - 1];
    sample = {};
    // note: at most m, in edge order, where many tie at the bound (a flat sea's, all 0).
    full_ids_.reserve(m);
    for (std::uint32_t h = 0; h < fv_.size() && full_ids_.size() < m; ++h) {
      if (candidate(h) && first[h] <= bound) full_ids_.push_back(h);
    }
    full_costs_.assign(full_ids_.size(), std::numeric_limits<double>::quiet_NaN());
    o_->for_ranges(full_ids_.size(), [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        Plan p;
        if (plan(full_ids_[i], p, true)) full_costs_[i] = p.cost;
      }
    });
  }

  // Edge e's full cost made by prepare_full_costs, or NaN.
  double made_cost(std::uint32_t e) const {
    const auto it = std::lower_bound(full_ids_.begin(), full_ids_.end(), e);
    return it != full_ids_.end() && *it == e
               ? full_costs_[static_cast<std::size_t>(it - full_ids_.begin())]
               : std::numeric_limits<double>::quiet_NaN();
  }

  // The queued edges' costs (lower bounds of their full costs), appended to out.
  void queued_costs(std::vector<float>& out) const {
    heap_.for_each_key([&](double key) { out.push_back(static_cast<float>(key)); });
  }

  // Collapses in cost order while more than keep vertices are left and the next collapse
  // costs at most max_cost.
  void run(std::size_t keep, QemResult& r,
           double max_cost = std::numeric_limits<double>::infinity()) {
    prepare(keep);
    const bool bounded = max_cost < std::numeric_limits<double>::infinity();
    run_max_cost_ = 0;
    const std::size_t start = alive_;
    const double span = start > keep ? static_cast<double>(start - keep) : 1.0;
    while (alive_ > keep && !heap_.empty()) {
      const double key = heap_.top_key();
      // note: keys are lower bounds of the full costs.
      if (bounded && !(key <= max_cost)) break;
      const std::uint32_t e = heap_.pop();
      // note: an interior edge queued again at its full cost, whose ends' stars no collapse
      // has touched since, comes up at that same cost: planned without the area term's walk
      // (its cost would be the key). An outline edge's choice of the end that goes weighs
      // the area term: planned in full.
      const bool same = full_at_[e] != kNone && opp_[e] != kNone &&
                        std::max(stamp_[src(e)], stamp_[dst(e)]) <= full_at_[e];
      // Its full cost made by prepare_full_costs, neither end's star changed since.
      const double made_at = !same && !full_ids_.empty() && (stamp_[src(e)] | stamp_[dst(e)]) == 0
                                 ? made_cost(e)
                                 : std::numeric_limits<double>::quiet_NaN();
      const bool made = std::isfinite(made_at);
      full_at_[e] = kNone;
      Plan p;
      if (!plan(e, p, !(same || made))) {
        ++r.refused;
        continue;
      }
      if (same) p.cost = key;
      if (made) {
        p.cost = made_at;
        ++r.full_costs_taken;
      }
      if (p.cost > key &&
          ((!heap_.empty() && p.cost > heap_.top_key()) || (bounded && !(p.cost <= max_cost)))) {
        heap_.set(e, p.cost);  // its cost went up since it was queued (see collapse): later
        full_at_[e] = collapses_;
        continue;
      }
      if (!plane_.empty() && !to_plane(p)) {
        ++r.refused;
        continue;
      }
      if (!valid(p)) {
        ++r.refused;
        continue;
      }
      collapse(p);
      run_max_cost_ = std::max(run_max_cost_, p.cost);
      ++r.collapses;
      if (r.collapses % 4096 == 0 && *progress_ &&
          !(*progress_)(static_cast<double>(r.collapses) / span, "simplify")) {
        throw Cancelled();
      }
    }
  }

  // The most a collapse of the last run() cost (0: none made).
  double run_max_cost() const { return run_max_cost_; }

  // The output (compacted), once run is done: the queue and the connectivity go first, so
  // that the output never sits beside them (the peak of the piece engine's merge).
  void result(QemResult& r) {
    heap_ = IndexedMinHeap();
    edges_ = {};
    full_at_ = {};
    full_ids_ = {};
    full_costs_ = {};
    stamp_ = {};
    mark_ = {};
    opp_ = {};
    out_ = {};
    const std::size_t n = xyz_.size() / 3;
    std::vector<std::uint32_t> id(n, kNone);
    std::size_t faces = 0;
    for (std::size_t f = 0; 3 * f < fv_.size(); ++f) faces += fv_[3 * f] == kNone ? 0 : 1;
    r.source.reserve(alive_);
    r.mesh.xyz.reserve(3 * alive_);
    r.quadrics.reserve(alive_);
    r.mesh.faces.reserve(faces);
    for (std::uint32_t v = 0; v < n; ++v) {
      if (flags_[v] & kGone) continue;
      id[v] = static_cast<std::uint32_t>(r.source.size());
      r.source.push_back(v);
      r.mesh.xyz.insert(r.mesh.xyz.end(), {xyz_[3 * v], xyz_[3 * v + 1], xyz_[3 * v + 2]});
      r.quadrics.push_back(q_[v]);
      if (!plane_.empty()) r.plane_xy.insert(r.plane_xy.end(), {plane_[2 * v], plane_[2 * v + 1]});
    }
    for (std::size_t f = 0; 3 * f < fv_.size(); ++f) {
      if (fv_[3 * f] == kNone) continue;
      r.mesh.faces.push_back({id[fv_[3 * f]], id[fv_[3 * f + 1]], id[fv_[3 * f + 2]]});
    }
  }

 private:
  // note: kBorder (on the outline) never changes while a vertex lives: the outline's vertices
  // stay on it (or go), and no collapse makes an interior vertex an outline one.
  static constexpr std::uint8_t kGone = 1, kLocked = 2, kPinched = 4, kBorder = 8, kFrozen = 16;

  // A collapse: half-edge h (a face's, from a to b) and the vertex that goes; the other one
  // stays, moved to x: vertex `at`'s position, or (kNone) an optimum. xy: x in the second
  // plane, if any.
  // note: x, xy, cost and source_goes are set by plan() (xy by to_plane()) before they are
  // read: left uninitialised (about 9M plans on San Gabriel to 10 %).
  struct Plan {
    std::uint32_t h = kNone;
    bool source_goes;
    double x[3];
    std::uint32_t at = kNone;
    double xy[2];
    double cost;
  };

  // p.xy from p.x: a vertex's plane position, or the caller's map of an optimum.
  bool to_plane(Plan& p) const {
    if (p.at != kNone) {
      p.xy[0] = plane_[2 * p.at], p.xy[1] = plane_[2 * p.at + 1];
      return true;
    }
    return o_->to_plane(p.x, p.xy);
  }

  const double* pos(std::uint32_t v) const { return &xyz_[3 * v]; }
  std::uint32_t src(std::uint32_t h) const { return fv_[h]; }
  std::uint32_t dst(std::uint32_t h) const { return fv_[next_of(h)]; }
  bool border(std::uint32_t v) const { return flags_[v] & kBorder; }
  bool locked(std::uint32_t v) const { return flags_[v] & kLocked; }
  bool pinched(std::uint32_t v) const { return flags_[v] & kPinched; }

  double face_area(std::uint32_t f) const {
    return area3(pos(fv_[3 * f]), pos(fv_[3 * f + 1]), pos(fv_[3 * f + 2]));
  }

  void link_opposites() {
    // The half-edges bucketed by their edge's lower vertex (a counting sort: a sort of all of
    // them was 4 % of qem's time), each with its higher vertex; within a bucket (a few), those
    // of one edge paired.
    const std::size_t n = xyz_.size() / 3, m = fv_.size();
    // Calls fn(h, lower, higher) for every half-edge, face by face.
    auto each = [&](auto&& fn) {
      for (std::uint32_t h = 0; h < m; h += 3) {
        const std::uint32_t v[3] = {fv_[h], fv_[h + 1], fv_[h + 2]};
        for (std::uint32_t k = 0; k < 3; ++k) {
          const std::uint32_t s = v[k], t = v[k == 2 ? 0 : k + 1];
          fn(h + k, std::min(s, t), std::max(s, t));
        }
      }
    };
    std::vector<std::uint32_t> first(n + 1, 0);
    each([&](std::uint32_t, std::uint32_t lo, std::uint32_t) { ++first[lo + 1]; });
    for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
    std::vector<std::uint64_t> by(m);  // (higher vertex << 32) | half-edge, by lower vertex
    {
      std::vector<std::uint32_t> at(first.begin(), first.end() - 1);
      each([&](std::uint32_t h, std::uint32_t lo, std::uint32_t hi) {
        by[at[lo]++] = std::uint64_t{hi} << 32 | h;
      });
    }
    opp_.assign(m, kNone);
    for (std::size_t v = 0; v < n; ++v) {
      for (std::uint32_t i = first[v]; i < first[v + 1]; ++i) {
        const auto h = static_cast<std::uint32_t>(by[i]);
        if (opp_[h] != kNone) continue;  // paired with an earlier one
        const std::uint64_t hi = by[i] >> 32;
        std::uint32_t g = kNone, count = 1;
        for (std::uint32_t j = i + 1; j < first[v + 1]; ++j) {
          if (by[j] >> 32 != hi) continue;
          if (++count == 2) g = static_cast<std::uint32_t>(by[j]);
        }
        if (count > 2) throw std::invalid_argument("qem: an edge has more than two faces");
        if (count == 2) {
          if (src(h) == src(g)) throw std::invalid_argument("qem: faces are not oriented alike");
          opp_[h] = g;
          opp_[g] = h;
        }
      }
    }
  }

  // The caller's pairing (o_->opposites), each pair checked: two half-edges of one edge, in
  // opposite directions.
  // note: a grid TIN's is known from its squares (grid_tin), where link_opposites' search
  // took 3.5 % of qem's instructions and 6 % of its branch misses; the pieces' pairing from
  // the grid, checked here: San Gabriel to 10 %, 9.33G -> 9.18G instructions, 56.7M -> 54.7M
  // branch misses (cachegrind).
  void adopt_opposites() {
    if (o_->opposites.size() != fv_.size()) {
      throw std::invalid_argument("qem: one opposite per half-edge");
    }
    opp_ = std::move(o_->opposites);
    const auto m = static_cast<std::uint32_t>(opp_.size());
    for (std::uint32_t h = 0; h < m; ++h) {
      const std::uint32_t g = opp_[h];
      if (g != kNone && !(g < m && opp_[g] == h && src(g) == dst(h) && dst(g) == src(h))) {
        throw std::invalid_argument("qem: opposite half-edges do not pair");
      }
    }
  }

  void init_quadrics() {
    const std::size_t n = xyz_.size() / 3;
    if (!o_->quadrics.empty()) {
      if (o_->quadrics.size() != n) throw std::invalid_argument("qem: one quadric per vertex");
      q_ = std::move(o_->quadrics);
      return;
    }
    // Triangle quadrics (the squared distance to each whole triangle's plane, weighted by its
    // size; plane quadrics with o_->plane_quadrics) and the outline's quadrics at weight 1 (by
    // default: o_->outline_weight): the outline cannot move anyway. On
    // st_helens_crater, 60 points x 3 sets, error x1e-4 at 10/30/50/70 %: plane quadrics,
    // outline weight 100: 18.5/5.68/2.72/1.21; triangle, 100: 18.3/5.75/2.56/1.09; triangle, 1:
    // 17.5/5.74/2.57/1.08 (probabilistic triangle quadrics: 66.8 at 10 %).
    q_.assign(n, Quadric{});
    for (std::uint32_t f = 0; 3 * f < fv_.size(); ++f) {
      if ((f & 0xFFFF) == 0xFFFF) check();
      const double* a = pos(fv_[3 * f]);
      const double* b = pos(fv_[3 * f + 1]);
      const double* c = pos(fv_[3 * f + 2]);
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      double nrm[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                       u[0] * v[1] - u[1] * v[0]};
      if (o_->plane_quadrics) {
        const double len = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        if (len > 0) nrm[0] /= len, nrm[1] /= len, nrm[2] /= len;
      }
      const Quadric tq = Quadric::plane(nrm, -(nrm[0] * a[0] + nrm[1] * a[1] + nrm[2] * a[2]));
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t h = 3 * f + k;
        q_[src(h)] += tq;
        if (opp_[h] != kNone || (locked(src(h)) && locked(dst(h)))) continue;
        // An outline edge: the plane through it, perpendicular to its face, at weight 1.
        const double* p = pos(src(h));
        const double* t = pos(dst(h));
        const double e[3] = {t[0] - p[0], t[1] - p[1], t[2] - p[2]};
        double m[3] = {e[1] * nrm[2] - e[2] * nrm[1], e[2] * nrm[0] - e[0] * nrm[2],
                       e[0] * nrm[1] - e[1] * nrm[0]};
        const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        if (len > 0) m[0] /= len, m[1] /= len, m[2] /= len;
        Quadric eq = Quadric::plane(m, -(m[0] * t[0] + m[1] * t[1] + m[2] * t[2]));
        if (o_->outline_weight != 1.0) eq *= o_->outline_weight;
        q_[src(h)] += eq;
        q_[dst(h)] += eq;
      }
    }
  }

  // Calls fn(h) for every half-edge out of v, counter-clockwise from out_[v] (from the outline
  // for a border vertex: its fan is then open). For a border vertex, also reports the last
  // face's edge into v through fn_in(h).
  template <typename F, typename G>
  void around(std::uint32_t v, F&& fn, G&& fn_in) const {
    around_from(out_[v], fn, fn_in);
  }

  // around(v, ...) from half-edge `first` out of v: out_[v], or for an interior vertex any.
  template <typename F, typename G>
  void around_from(std::uint32_t first, F&& fn, G&& fn_in) const {
    std::uint32_t h = first;
    for (;;) {
      fn(h);
      const std::uint32_t p = prev_of(h);
      const std::uint32_t g = opp_[p];
      if (g == kNone) {
        fn_in(p);
        return;
      }
      h = g;
      if (h == first) return;
    }
  }

  // Neighbours of a vertex (into a small buffer), counter-clockwise from dst(first): first is
  // as around_from's.
  int neighbours(std::uint32_t first, std::uint32_t* buf, int cap) const {
    int k = 0;
    around_from(
        first,
        [&](std::uint32_t h) {
          if (k < cap) buf[k++] = dst(h);
        },
        [&](std::uint32_t p) {
          if (k < cap) buf[k++] = src(p);
        });
    return k;
  }

  // A border vertex's outline neighbours: next (its outline edge out) and prev (in).
  bool straight(std::uint32_t v) const {
    if (locked(v) || pinched(v) || !border(v)) return false;
    const std::uint32_t next = dst(out_[v]);
    std::uint32_t prev = kNone;
    around(
        v, [](std::uint32_t) {}, [&](std::uint32_t p) { prev = src(p); });
    if (prev == kNone || prev == next) return false;
    if (o_->outline_collinear ? !o_->outline_collinear(next, v, prev)
                              : orient(pos(next), pos(v), pos(prev)) != CGAL::COLLINEAR) {
      return false;
    }
    return !o_->outline_chord_ok || o_->outline_chord_ok(next, prev);
  }

  // Quadric cost plus the area term for moving both ends of h to x (area false: the quadric's
  // cost alone).
  double cost(std::uint32_t h, const Quadric& q, const double* x, bool area = true) const {
    if (!area || o_->area_weight == 0) return q(x);
    const std::uint32_t a = src(h), b = dst(h);
    const std::uint32_t fl = h / 3, fr = opp_[h] == kNone ? kNone : opp_[h] / 3;
    // note: a face's area is made again from its corners, the positions the walk reads anyway,
    // beside the moved face's in the other lane: the same bits as an array of areas kept up
    // to date, whose load missed the caches as often as a corner's (perf: a tenth of cost's
    // samples) and whose upkeep took a square root a face round every collapse.
    double before = face_area(fl) + (fr != kNone ? face_area(fr) : 0.0), after = 0;
    for (const std::uint32_t v : {a, b}) {
      around(
          v,
          [&](std::uint32_t g) {
            const std::uint32_t f = g / 3;
            if (f == fl || f == fr) return;
            double face, moved;
            area3_pair(pos(fv_[3 * f]), pos(fv_[3 * f + 1]), pos(fv_[3 * f + 2]), x, pos(dst(g)),
                       pos(fv_[prev_of(g)]), face, moved);
            before += face;
            after += moved;
          },
          [](std::uint32_t) {});
    }
    const double d = after - before;
    return q(x) + o_->area_weight * d * d;
  }

  // The collapse of edge h (either half-edge) the rules allow, and its cost (area false: without
  // the area term); false if none.
  bool plan(std::uint32_t h, Plan& p, bool area = true) const {
    const std::uint32_t a = src(h), b = dst(h);
    if ((flags_[a] | flags_[b]) & (kPinched | kFrozen)) return false;
    const bool ba = border(a), bb = border(b);
    const bool fixed_a = ba || locked(a), fixed_b = bb || locked(b);
    const Quadric q = sum(q_[a], q_[b]);
    p.h = h;
    if (!fixed_a && !fixed_b) {
      optimum(q, pos(a), pos(b), p.x);
      p.source_goes = true;
      p.cost = cost(h, q, p.x, area);
      return std::isfinite(p.cost);
    }
    if (opp_[h] != kNone) {
      // An interior edge: onto its fixed end; between two fixed ends it would pinch.
      if (fixed_a && fixed_b) return false;
      const std::uint32_t stay = fixed_a ? a : b;
      std::copy(pos(stay), pos(stay) + 3, p.x);
      p.at = stay;
      p.source_goes = !fixed_a;
      p.cost = cost(h, q, p.x, area);
      return true;
    }
    // An outline edge: one end goes, if the outline runs straight through it.
    bool found = false;
    for (const bool source_goes : {true, false}) {
      const std::uint32_t gone = source_goes ? a : b, stay = source_goes ? b : a;
      if (!straight(gone)) continue;
      const double c = cost(h, q, pos(stay), area);
      if (!found || c < p.cost) {
        found = true;
        p.cost = c;
        p.source_goes = source_goes;
        std::copy(pos(stay), pos(stay) + 3, p.x);
        p.at = stay;
      }
    }
    return found;
  }

  // Topology (the link condition, no ear removed) and geometry (no fold, the bound).
  bool valid(const Plan& p) {
    const std::uint32_t h = p.h, a = src(h), b = dst(h);
    const std::uint32_t g = opp_[h];
    const std::uint32_t o1 = opp_[next_of(h)], o2 = opp_[prev_of(h)];
    if (o1 == kNone && o2 == kNone) return false;
    std::uint32_t c = dst(next_of(h)), d = kNone;
    if (g != kNone) {
      if (opp_[next_of(g)] == kNone && opp_[prev_of(g)] == kNone) return false;
      d = dst(next_of(g));
      if (border(a) && border(b)) return false;
    }
    // note: a vertex of more than 64 neighbours is left alone (the rings stay bounded).
    constexpr int kCap = 64;
    std::uint32_t na[kCap], nb[kCap];
    // An interior end's ring from the other end (its first neighbour): the edge's own faces
    // are then its first and last, known without a test (see fans_ok).
    const bool ring_a = !border(a), ring_b = g != kNone && !border(b);
    const int ka = neighbours(ring_a ? h : out_[a], na, kCap);
    const int kb = neighbours(ring_b ? g : out_[b], nb, kCap);
    if (ka + kb > kCap) return false;
    // note: the common neighbours found by marking a's (a ring holds no vertex twice), not by
    // testing every pair: the pair loop's exits were 9 % of qem's branch misses (cachegrind).
    if (++ring_mark_ == 0) {
      std::fill(mark_.begin(), mark_.end(), 0);
      ring_mark_ = 1;
    }
    for (int i = 0; i < ka; ++i) mark_[na[i]] = ring_mark_;
    int common = 0;
    for (int j = 0; j < kb; ++j) {
      if (mark_[nb[j]] != ring_mark_) continue;
      if (nb[j] != c && nb[j] != d) return false;
      ++common;
    }
    if (common != (g == kNone ? 1 : 2)) return false;
    // The faces round a and b but the edge's own, with the moving corner at x: the faces round
    // v lie between its consecutive neighbours (na, nb are counter-clockwise; a border vertex's
    // fan is open), and those holding the other end are the edge's own.
    // Corners counter-clockwise with the moving one in the middle.
    auto face_ok = [&](std::uint32_t rv, std::uint32_t sv) {
      const double* r = pos(rv);
      const double* s = pos(sv);
      if (orient(s, p.x, r) != CGAL::LEFT_TURN || too_thin(s, p.x, r)) return false;
      if (plane_.empty()) return !o_->triangle_ok || o_->triangle_ok(s, p.x, r);
      const double* ps = &plane_[2 * sv];
      const double* pr = &plane_[2 * rv];
      const double s3[3] = {ps[0], ps[1], s[2]}, x3[3] = {p.xy[0], p.xy[1], p.x[2]},
                   r3[3] = {pr[0], pr[1], r[2]};
      if (orient(s3, x3, r3) != CGAL::LEFT_TURN) return false;
      return !o_->triangle_ok || o_->triangle_ok(s3, x3, r3);
    };
    // note: from the other end (ring), the faces between are 1 .. k - 2; else each face is
    // tested for the other end (that test's branch missed often: cachegrind).
    auto fans_ok = [&](std::uint32_t v, const std::uint32_t* nv, int k, std::uint32_t other,
                       bool ring) {
      if (p.x[0] == pos(v)[0] && p.x[1] == pos(v)[1] && p.x[2] == pos(v)[2]) return true;
      if (ring) {
        for (int i = 1; i + 1 < k; ++i) {
          if (!face_ok(nv[i], nv[i + 1])) return false;
        }
        return true;
      }
      const int faces = border(v) ? k - 1 : k;
      for (int i = 0; i < faces; ++i) {
        const std::uint32_t rv = nv[i], sv = nv[i + 1 == k ? 0 : i + 1];
        if (rv == other || sv == other) continue;
        if (!face_ok(rv, sv)) return false;
      }
      return true;
    };
    return fans_ok(a, na, ka, b, ring_a) && fans_ok(b, nb, kb, a, ring_b);
  }

  // A new face no thicker than kMinHeight frame units (a cell's side is about one): exact
  // orientation accepts a face a rounding error away from flat (an optimum nearly on the
  // line of two corners), which the map to the output CRS can fold (2 faces of peru_mongon
  // at 70 %, flat or clockwise in UTM). Its height over its longest side decides.
  static bool too_thin(const double* s, const double* x, const double* r) {
    constexpr double kMinHeight = 1e-5;
    const double ux = x[0] - s[0], uy = x[1] - s[1], vx = r[0] - s[0], vy = r[1] - s[1];
    const double wx = r[0] - x[0], wy = r[1] - x[1];
    const double longest2 = std::max({ux * ux + uy * uy, vx * vx + vy * vy, wx * wx + wy * wy});
    return ux * vy - uy * vx <= kMinHeight * std::sqrt(longest2);
  }

  // Whether h is its edge's half-edge of the two (the lower), or its only one.
  // note: kNone is above every half-edge, so one compare (the two were a branch that missed).
  bool first_edge(std::uint32_t h) const { return opp_[h] > h; }

  // The edge's lower half-edge (kNone is above every half-edge: an outline edge's own).
  std::uint32_t canonical(std::uint32_t h) const { return std::min(opp_[h], h); }

  void normalize_out(std::uint32_t v) {
    // Turn clockwise to the outline edge out of v, if there is one.
    // note: an interior vertex has none (the walk would come back to out_[v]).
    if (!border(v)) return;
    const std::uint32_t first = out_[v];
    std::uint32_t h = first;
    for (;;) {
      const std::uint32_t g = opp_[h];
      if (g == kNone) break;
      h = next_of(g);
      if (h == first) break;
    }
    out_[v] = h;
  }

  void collapse(const Plan& p) {
    const std::uint32_t h = p.h;
    const std::uint32_t gone = p.source_goes ? src(h) : dst(h);
    const std::uint32_t stay = p.source_goes ? dst(h) : src(h);
    const std::uint32_t g = opp_[h];
    const std::uint32_t fl = h / 3, fr = g == kNone ? kNone : g / 3;
    // The edges of the two faces leave the queue.
    for (const std::uint32_t f : {fl, fr}) {
      if (f == kNone) continue;
      for (std::uint32_t k = 0; k < 3; ++k) heap_.erase(canonical(3 * f + k));
    }
    // The gone vertex's corners become the staying vertex's.
    around(
        gone, [&](std::uint32_t e) { fv_[e] = stay; }, [](std::uint32_t) {});
    // Each face's two other edges become one: their outer half-edges face each other.
    std::uint32_t survivors[4];
    int ns = 0;
    for (const std::uint32_t f : {fl, fr}) {
      if (f == kNone) continue;
      std::uint32_t outer[2] = {kNone, kNone};
      int k = 0;
      for (std::uint32_t e = 3 * f; e < 3 * f + 3; ++e) {
        if (e == h || e == g) continue;
        outer[k++] = opp_[e];
      }
      if (outer[0] != kNone) opp_[outer[0]] = outer[1];
      if (outer[1] != kNone) opp_[outer[1]] = outer[0];
      for (const std::uint32_t o : outer) {
        if (o != kNone) survivors[ns++] = o;
      }
      for (std::uint32_t e = 3 * f; e < 3 * f + 3; ++e) {
        fv_[e] = kNone;
        opp_[e] = kNone;
      }
    }
    flags_[gone] |= kGone;
    out_[gone] = kNone;
    --alive_;
    for (int i = 0; i < ns; ++i) {
      out_[src(survivors[i])] = survivors[i];
      out_[dst(survivors[i])] = next_of(survivors[i]);
    }
    for (int i = 0; i < ns; ++i) {
      normalize_out(src(survivors[i]));
      normalize_out(dst(survivors[i]));
    }
    q_[stay] += q_[gone];
    ++collapses_;
    std::copy(p.x, p.x + 3, &xyz_[3 * stay]);
    if (!plane_.empty()) std::copy(p.xy, p.xy + 2, &plane_[2 * stay]);
    // note: stay and its neighbours are the vertices whose stars changed (a face, a corner's
    // position, a quadric): the plans of the edges at them.
    stamp_[stay] = collapses_;
    around(
        stay, [&](std::uint32_t e) { stamp_[dst(e)] = collapses_; },
        [&](std::uint32_t e) { stamp_[src(e)] = collapses_; });
    // New costs for the edges at stay: their quadric and optimum changed.
    // note: the other edges whose star holds a face at stay (between two of its neighbours,
    // and from a neighbour outwards) changed only through the area term. They are not
    // requeued here: each is re-costed when it comes up and requeued if its cost rose. That
    // halves the work per collapse again (outward edges alone: kilauea to 10 %, 11.1 s to
    // 5.8 s; the ring's edges too: san_gabriel to 10 %, 3.5 s to 2.35 s of CPU) at the same
    // errors (default measure x1e-4, st_helens_crater 10/50 %: 16.7/2.51 to 16.9/2.50,
    // zion_canyon 25.8/4.17 to 24.7/4.16). Fully lazy (the edges at stay too, requeued when
    // they come up) plans fewer but pops 2.5 x as often: no faster.
    edges_.clear();
    if (!(flags_[stay] & kPinched)) {
      around(
          stay, [&](std::uint32_t e) { edges_.push_back(canonical(e)); },
          [&](std::uint32_t e) { edges_.push_back(canonical(e)); });
    }
    // note: the quadrics (80 bytes, two cache lines) and positions of stay's neighbours are
    // mostly out of the caches: ask for all of them before the first plan needs one.
    for (const std::uint32_t e : edges_) {
      const std::uint32_t v = src(e) ^ dst(e) ^ stay;  // the end that is not stay
      const char* q = reinterpret_cast<const char*>(&q_[v]);
      __builtin_prefetch(q);
      __builtin_prefetch(q + sizeof(Quadric) - 1);
      __builtin_prefetch(pos(v));
    }
    for (const std::uint32_t e : edges_) update(e);
  }

  void update(std::uint32_t e) {
    Plan p;
    // note: queued at the quadric's cost alone, a lower bound (the area term is a square), so
    // the edge comes up no later than its full cost would bring it; run() costs it in full
    // then and queues it again if that rose past the next edge. One star walked per edge that
    // comes up, not two per edge at stay: San Gabriel to 10 %, 10-15 % less CPU; the default
    // measure (60 points x 3 sets) on st_helens_crater, zion_canyon and peru_mongon at 10 and
    // 50 % moved by -1.6 % to +0.7 %.
    full_at_[e] = kNone;
    if (plan(e, p, false)) {
      heap_.set(e, p.cost);
    } else {
      heap_.erase(e);
    }
  }

  // Asks progress whether to go on (Cancelled if not), before the first collapse (run() asks
  // it every 4096 collapses, with the fraction done).
  void check() const {
    if (*progress_ && !(*progress_)(0.0, "simplify")) throw Cancelled();
  }

  // note: pointers, not references: a copy (QemCollapse::copy) points them at its own.
  QemOptions* o_;
  const Progress* progress_;
  std::vector<double> xyz_;
  std::vector<double> plane_;  // per vertex x, y in the second plane (empty: none)
  std::vector<std::uint32_t> fv_, opp_, out_;
  std::vector<std::uint8_t> flags_;
  std::vector<Quadric> q_;
  std::size_t alive_ = 0;
  IndexedMinHeap heap_;
  std::vector<std::uint32_t> edges_;  // scratch: the edges one collapse updates
  // Per edge (its queue id) queued at its full cost: the collapses done then, else kNone; per
  // vertex, the collapses done when its star last changed (run()'s shortcut).
  std::vector<std::uint32_t> full_at_, stamp_;
  // The edges (queue ids, ascending) given their first cost in full by prepare_full_costs,
  // and those costs (NaN where the plan failed).
  std::vector<std::uint32_t> full_ids_;
  std::vector<double> full_costs_;
  // Per vertex: valid()'s mark of the first end's neighbours (ring_mark_ for this test).
  std::vector<std::uint32_t> mark_;
  std::uint32_t ring_mark_ = 0;
  std::uint32_t collapses_ = 0;
  double run_max_cost_ = 0;
  bool prepared_ = false;
};

}  // namespace

struct QemCollapse::Impl {
  Impl(TriMesh&& mesh, QemOptions&& options, Progress&& progress)
      : o(std::move(options)), p(std::move(progress)), c(std::move(mesh), o, p) {}
  Impl(const Impl& other) : o(other.o), p(other.p), c(other.c) { c.rebind(o, p); }
  QemOptions o;
  const Progress p;  // the collapser keeps references to both
  Collapser c;
};

QemCollapse::QemCollapse(TriMesh mesh, QemOptions options, Progress progress)
    : impl_(std::make_unique<Impl>(std::move(mesh), std::move(options), std::move(progress))) {
  impl_->c.prepare();
  r_.input_vertices = impl_->c.alive();
}
QemCollapse::QemCollapse(const QemCollapse& other)
    : impl_(std::make_unique<Impl>(*other.impl_)), r_(other.r_) {}
QemCollapse::~QemCollapse() = default;
QemCollapse::QemCollapse(QemCollapse&&) noexcept = default;
QemCollapse& QemCollapse::operator=(QemCollapse&&) noexcept = default;

std::size_t QemCollapse::vertices() const { return impl_->c.alive(); }

double QemCollapse::max_cost_made() const { return impl_->c.run_max_cost(); }

void QemCollapse::queued_costs(std::vector<float>& out) const { impl_->c.queued_costs(out); }

std::size_t QemCollapse::collapse(std::size_t keep, double max_cost) {
  const std::size_t before = r_.collapses;
  impl_->c.run(keep, r_, max_cost);
  return r_.collapses - before;
}

QemResult QemCollapse::result() {
  impl_->c.result(r_);
  impl_.reset();
  return std::move(r_);
}

QemResult qem_simplify(TriMesh mesh, std::size_t keep, QemOptions options, const Progress& progress,
                       double max_cost) {
  QemResult r;
  Collapser c(std::move(mesh), options, progress);
  r.input_vertices = c.alive();
  c.run(keep, r, max_cost);
  c.result(r);
  if (progress && !progress(1.0, "simplify")) throw Cancelled();
  return r;
}

}  // namespace dpts::core

// Grid TIN construction, uniform sampling on a TIN, bucket-grid point location.
#include "core/surface_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/footprint.hpp"
#include "core/random.hpp"

namespace dpts::core {
namespace {

double cross2(const double* a, const double* b, const double* c) {
  return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

// Face f's corners b, c and the point (x, y) relative to its corner a (so that large UTM
// coordinates cost no precision in the differences), and twice its signed area in x, y.
struct Relative {
  const double *a = nullptr, *b = nullptr, *c = nullptr;
  double bx = 0, by = 0, cx = 0, cy = 0, px = 0, py = 0, area = 0;
};
Relative relative(const TriMesh& m, std::uint32_t f, double x, double y) {
  Relative r;
  r.a = &m.xyz[3 * m.faces[f][0]], r.b = &m.xyz[3 * m.faces[f][1]], r.c = &m.xyz[3 * m.faces[f][2]];
  r.bx = r.b[0] - r.a[0], r.by = r.b[1] - r.a[1], r.cx = r.c[0] - r.a[0], r.cy = r.c[1] - r.a[1];
  r.px = x - r.a[0], r.py = y - r.a[1];
  r.area = r.bx * r.cy - r.by * r.cx;
  return r;
}

// Barycentric lift of (x, y) onto face f.
SurfacePoint lift(const TriMesh& m, std::uint32_t f, double x, double y) {
  const Relative r = relative(m, f, x, y);
  const double lb = (r.px * r.cy - r.py * r.cx) / r.area, lc = (r.bx * r.py - r.by * r.px) / r.area;
  return {x, y, r.a[2] + lb * (r.b[2] - r.a[2]) + lc * (r.c[2] - r.a[2]), f};
}

// Whether (x, y) lies in face f, its edges included: each edge's orientation test computed
// relative to the first corner, with a tolerance for the rounding of the coordinates themselves
// (a point given on an edge is off it by up to half an ulp of its coordinates: 1e-9 m at 5e6 m)
// and of the arithmetic. note: a face flat in x, y (area within that tolerance) contains
// nothing: its points lie on its neighbours, and it cannot lift them.
enum class Inside { no, yes, degenerate };
Inside contains(const TriMesh& m, std::uint32_t f, double x, double y) {
  const Relative r = relative(m, f, x, y);
  const double *a = r.a, bx = r.bx, by = r.by, cx = r.cx, cy = r.cy, px = r.px, py = r.py;
  const double area = r.area;
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  const double magnitude = std::max({std::fabs(a[0]), std::fabs(a[1]), std::fabs(x), std::fabs(y)});
  const double size = std::max({std::fabs(bx), std::fabs(by), std::fabs(cx), std::fabs(cy)});
  if (!(std::fabs(area) > 8.0 * kEps * size * (magnitude + size))) return Inside::degenerate;
  const double extent = std::max({size, std::fabs(px), std::fabs(py)});
  const double tol = 8.0 * kEps * extent * (magnitude + extent);
  const double sign = area > 0 ? 1.0 : -1.0;
  const double ab = sign * (bx * py - by * px);                              // edge a-b
  const double bc = sign * ((cx - bx) * (py - by) - (cy - by) * (px - bx));  // edge b-c
  const double ca = sign * (px * cy - py * cx);                              // edge c-a
  return ab >= -tol && bc >= -tol && ca >= -tol ? Inside::yes : Inside::no;
}

// The point of segment a-b nearest to p in x, y, into q; returns its squared distance.
double closest_on_segment(const double* p, const double* a, const double* b, double* q) {
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  const double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  q[0] = a[0] + t * dx, q[1] = a[1] + t * dy;
  return (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]);
}

}  // namespace

Diagonal delaunay_diagonal(const GridFrame& f) {
  // Every square maps to the same parallelogram; Delaunay takes its shorter diagonal (the
  // angles facing the longer one are obtuse), and on a tie CGAL's perturbation takes NW-SE.
  const double nw_u = f.u(1, 1), nw_w = f.w(1, 1), ne_u = f.u(-1, 1), ne_w = f.w(-1, 1);
  return ne_u * ne_u + ne_w * ne_w < nw_u * nw_u + nw_w * nw_w ? Diagonal::ne_sw : Diagonal::nw_se;
}

Tin grid_tin(const HeightGrid& g, Diagonal diagonal, std::vector<std::uint32_t>* opposites) {
  Tin t;
  t.cells = surface_cells(g);
  // Surface cell -> vertex index.
  std::vector<std::uint32_t> index(g.cell_count(), 0xFFFFFFFFu);
  for (std::uint32_t i = 0; i < t.cells.size(); ++i) index[t.cells[i]] = i;
  // note: two faces a cell at most; grown by push_back the array would hold up to twice that.
  t.faces.reserve(2 * static_cast<std::size_t>(std::max(g.width - 1, 0)) *
                  static_cast<std::size_t>(std::max(g.height - 1, 0)));
  // With opposites: each square's half-edge on its south side, for the square below (a row),
  // and on its east side, for the square to the right.
  std::vector<std::uint32_t> south(static_cast<std::size_t>(std::max(g.width - 1, 0)), kNoOpposite);
  // note: sized for two faces a square, cut to the faces at the end (grown a square at a time
  // it was reallocated and filled as often as the faces).
  if (opposites) opposites->assign(3 * t.faces.capacity(), kNoOpposite);
  auto pair = [&](std::uint32_t h, std::uint32_t o) {
    if (h == kNoOpposite || o == kNoOpposite) return;
    (*opposites)[h] = o;
    (*opposites)[o] = h;
  };
  for (int r = 0; r + 1 < g.height; ++r) {
    std::uint32_t east = kNoOpposite;  // the square to the left's
    for (int c = 0; c + 1 < g.width; ++c) {
      // Corners: a = (c,r) NW, b = (c+1,r) NE, s = (c,r+1) SW, d = (c+1,r+1) SE.
      const bool va = g.is_valid(c, r), vb = g.is_valid(c + 1, r);
      const bool vs = g.is_valid(c, r + 1), vd = g.is_valid(c + 1, r + 1);
      const std::uint32_t a = index[g.index(c, r)], b = index[g.index(c + 1, r)];
      const std::uint32_t s = index[g.index(c, r + 1)], d = index[g.index(c + 1, r + 1)];
      const int n = va + vb + vs + vd;
      const auto h0 = static_cast<std::uint32_t>(3 * t.faces.size());  // first new half-edge
      // The square's half-edges on its sides (kNoOpposite: no face there).
      std::uint32_t north = kNoOpposite, west = kNoOpposite, to_south = kNoOpposite,
                    to_east = kNoOpposite;
      if (n == 4 && diagonal == Diagonal::nw_se) {
        t.faces.push_back({a, s, d});  // a-s west, s-d south, d-a diagonal
        t.faces.push_back({a, d, b});  // a-d diagonal, d-b east, b-a north
        west = h0, to_south = h0 + 1, to_east = h0 + 4, north = h0 + 5;
        if (opposites) pair(h0 + 2, h0 + 3);
      } else if (n == 4) {
        t.faces.push_back({a, s, b});  // a-s west, s-b diagonal, b-a north
        t.faces.push_back({b, s, d});  // b-s diagonal, s-d south, d-b east
        west = h0, north = h0 + 2, to_south = h0 + 4, to_east = h0 + 5;
        if (opposites) pair(h0 + 1, h0 + 3);
      } else if (n == 3) {
        if (!va) t.faces.push_back({b, s, d}), to_south = h0 + 1, to_east = h0 + 2;
        if (!vb) t.faces.push_back({a, s, d}), west = h0, to_south = h0 + 1;
        if (!vs) t.faces.push_back({a, d, b}), to_east = h0 + 1, north = h0 + 2;
        if (!vd) t.faces.push_back({a, s, b}), west = h0, north = h0 + 2;
      }
      if (opposites) {
        pair(north, south[c]);
        pair(west, east);
        south[c] = to_south;
        east = to_east;
      }
    }
  }
  t.faces.shrink_to_fit();
  if (opposites) {
    opposites->resize(3 * t.faces.size());
    opposites->shrink_to_fit();
  }
  return t;
}

void fix_orientation(TriMesh& m, std::vector<std::uint32_t>* opposites) {
  std::vector<char> reversed;
  if (opposites) reversed.assign(m.faces.size(), 0);
  for (std::size_t i = 0; i < m.faces.size(); ++i) {
    auto& f = m.faces[i];
    if (cross2(&m.xyz[3 * f[0]], &m.xyz[3 * f[1]], &m.xyz[3 * f[2]]) < 0) {
      std::swap(f[1], f[2]);
      if (opposites) reversed[i] = 1;
    }
  }
  if (!opposites || std::find(reversed.begin(), reversed.end(), 1) == reversed.end()) return;
  // Face (v0, v1, v2) reversed to (v0, v2, v1): its half-edge k (on corners k, k + 1) is now
  // its half-edge 2 - k.
  auto renumber = [&](std::uint32_t h) {
    if (h == kNoOpposite || !reversed[h / 3]) return h;
    return h - h % 3 + (2 - h % 3);
  };
  std::vector<std::uint32_t> renumbered(opposites->size(), kNoOpposite);
  for (std::uint32_t h = 0; h < opposites->size(); ++h) {
    renumbered[renumber(h)] = renumber((*opposites)[h]);
  }
  *opposites = std::move(renumbered);
}

std::vector<SurfacePoint> sample_uniform(const TriMesh& m, std::size_t count, std::uint64_t seed) {
  std::vector<double> cdf(m.faces.size());
  double total = 0.0;
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    total += 0.5 * std::fabs(cross2(&m.xyz[3 * m.faces[f][0]], &m.xyz[3 * m.faces[f][1]],
                                    &m.xyz[3 * m.faces[f][2]]));
    cdf[f] = total;
  }
  SplitMix rng{seed};
  std::vector<SurfacePoint> pts;
  for (std::size_t k = 0; k < count && total > 0; ++k) {
    const double u = rng.uniform() * total;
    const auto f = static_cast<std::uint32_t>(std::min<std::size_t>(
        std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin(), cdf.size() - 1));
    // Uniform in the triangle: reflect the unit square's upper half.
    double r1 = rng.uniform(), r2 = rng.uniform();
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    const double* a = &m.xyz[3 * m.faces[f][0]];
    const double* b = &m.xyz[3 * m.faces[f][1]];
    const double* c = &m.xyz[3 * m.faces[f][2]];
    const double x = a[0] + r1 * (b[0] - a[0]) + r2 * (c[0] - a[0]);
    const double y = a[1] + r1 * (b[1] - a[1]) + r2 * (c[1] - a[1]);
    pts.push_back(lift(m, f, x, y));
  }
  return pts;
}

PointLocator::PointLocator(const TriMesh& mesh) : mesh_(mesh) {
  double x1 = -std::numeric_limits<double>::infinity(), y1 = x1;
  x0_ = y0_ = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < mesh.vertex_count(); ++v) {
    x0_ = std::min(x0_, mesh.xyz[3 * v]), x1 = std::max(x1, mesh.xyz[3 * v]);
    y0_ = std::min(y0_, mesh.xyz[3 * v + 1]), y1 = std::max(y1, mesh.xyz[3 * v + 1]);
  }
  if (mesh.faces.empty()) return;
  // About two faces per bucket; for a thin or flat mesh, at most 4 buckets per face along its
  // longer side (so the bucket counts stay small whatever the shape).
  const double faces = static_cast<double>(mesh.faces.size());
  const double w = x1 - x0_, h = y1 - y0_;
  cell_ = std::max({std::sqrt(2.0 * w * h / faces), std::max(w, h) / (4.0 * faces),
                    std::numeric_limits<double>::min()});
  nx_ = std::max(1, static_cast<int>(std::ceil((x1 - x0_) / cell_)) + 1);
  ny_ = std::max(1, static_cast<int>(std::ceil((y1 - y0_) / cell_)) + 1);
  const double pad =
      16 * std::numeric_limits<double>::epsilon() *
      (std::max({std::fabs(x0_), std::fabs(x1), std::fabs(y0_), std::fabs(y1)}) + std::max(w, h));
  std::vector<std::pair<std::uint32_t, std::uint32_t>> entries;  // (bucket, face)
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    double fx0 = 1e300, fx1 = -1e300, fy0 = 1e300, fy1 = -1e300;
    for (auto v : mesh.faces[f]) {
      fx0 = std::min(fx0, mesh.xyz[3 * v]), fx1 = std::max(fx1, mesh.xyz[3 * v]);
      fy0 = std::min(fy0, mesh.xyz[3 * v + 1]), fy1 = std::max(fy1, mesh.xyz[3 * v + 1]);
    }
    // note: padded by the edge tolerance of contains(), so that a point it finds on an edge
    // (up to rounding, maybe a hair outside the box) is in one of the face's buckets.
    const int i0 = std::max(0, static_cast<int>((fx0 - pad - x0_) / cell_)),
              i1 = std::min(nx_ - 1, static_cast<int>((fx1 + pad - x0_) / cell_));
    const int j0 = std::max(0, static_cast<int>((fy0 - pad - y0_) / cell_)),
              j1 = std::min(ny_ - 1, static_cast<int>((fy1 + pad - y0_) / cell_));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i)
        entries.emplace_back(static_cast<std::uint32_t>(j * nx_ + i), f);
    }
  }
  std::sort(entries.begin(), entries.end());
  first_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
  for (const auto& e : entries) ++first_[e.first + 1];
  for (std::size_t b = 0; b + 1 < first_.size(); ++b) first_[b + 1] += first_[b];
  faces_.reserve(entries.size());
  for (const auto& e : entries) faces_.push_back(e.second);
}

std::optional<PointLocator::Hit> PointLocator::locate(double x, double y, double snap) const {
  const double p[2] = {x, y};
  // Bucket coordinates in 64 bits, clamped (a far or non-finite point is in no bucket).
  auto bucket = [](double t) {
    constexpr double kFar = 1e15;
    return static_cast<long long>(std::floor(std::isnan(t) ? -kFar : std::clamp(t, -kFar, kFar)));
  };
  const long long reach = snap > 0 ? bucket(std::ceil(snap / cell_)) : 0;
  const long long ci = bucket((x - x0_) / cell_), cj = bucket((y - y0_) / cell_);
  double best_d2 = snap * snap;
  std::optional<std::uint32_t> nearest;
  for (long long j = std::max(0LL, cj - reach); j <= std::min<long long>(ny_ - 1, cj + reach);
       ++j) {
    for (long long i = std::max(0LL, ci - reach); i <= std::min<long long>(nx_ - 1, ci + reach);
         ++i) {
      const std::size_t b = static_cast<std::size_t>(j) * nx_ + i;
      for (std::uint32_t k = first_[b]; k < first_[b + 1]; ++k) {
        const std::uint32_t f = faces_[k];
        const Inside in = contains(mesh_, f, x, y);
        if (in == Inside::degenerate) continue;
        if (i == ci && j == cj && in == Inside::yes) return Hit{lift(mesh_, f, x, y), false};
        if (snap > 0) {
          const double* a = &mesh_.xyz[3 * mesh_.faces[f][0]];
          const double* bb = &mesh_.xyz[3 * mesh_.faces[f][1]];
          const double* c = &mesh_.xyz[3 * mesh_.faces[f][2]];
          double q[2];
          const double d2 =
              std::min({closest_on_segment(p, a, bb, q), closest_on_segment(p, bb, c, q),
                        closest_on_segment(p, c, a, q)});
          if (d2 <= best_d2 && (!nearest || d2 < best_d2 || f < *nearest))
            best_d2 = d2, nearest = f;
        }
      }
    }
  }
  if (!nearest) return std::nullopt;
  // Snap onto the nearest face: its closest point, then lift.
  const auto& F = mesh_.faces[*nearest];
  const double* corner[3] = {&mesh_.xyz[3 * F[0]], &mesh_.xyz[3 * F[1]], &mesh_.xyz[3 * F[2]]};
  double snapped[2] = {x, y}, sd2 = std::numeric_limits<double>::infinity();
  for (int e = 0; e < 3; ++e) {
    double q[2];
    const double d2 = closest_on_segment(p, corner[e], corner[(e + 1) % 3], q);
    if (d2 < sd2) sd2 = d2, snapped[0] = q[0], snapped[1] = q[1];
  }
  return Hit{lift(mesh_, *nearest, snapped[0], snapped[1]), true};
}

TriMesh frame_grid_mesh(const HeightGrid& grid, const GridFrame& frame) {
  const Tin tin = grid_tin(grid, delaunay_diagonal(frame));
  TriMesh mesh;
  if (tin.faces.empty()) return mesh;
  const double unit = frame.metres_per_unit;
  mesh.xyz.reserve(3 * tin.cells.size());
  for (const std::uint32_t cell : tin.cells) {
    const int c = static_cast<int>(cell % static_cast<std::uint32_t>(grid.width));
    const int r = static_cast<int>(cell / static_cast<std::uint32_t>(grid.width));
    mesh.xyz.insert(mesh.xyz.end(), {frame.u(c, r), frame.w(c, r), grid.z[cell] / unit});
  }
  mesh.faces = tin.faces;
  fix_orientation(mesh);
  return mesh;
}

}  // namespace dpts::core

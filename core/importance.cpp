// VP and PLD importance of a vertex (the DPTS paper, sections 4.1 and 4.2).
#include "core/importance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/random.hpp"

namespace dpts::core {
namespace {

struct P2 {
  double x, y;
};

double cross(P2 o, P2 a, P2 b) { return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x); }

// Plane z = a x + b y + c through three points (degenerate triangles give a flat plane at
// their mean height; they have no area and contribute nothing anyway).
// note: no member initializers, so that vp_volume_exact's array of them is not zeroed a call.
struct Plane {
  double a, b, c;
  double at(double x, double y) const { return a * x + b * y + c; }
};

Plane plane_through(const Point3& p, const Point3& q, const Point3& r) {
  const double ux = q.x - p.x, uy = q.y - p.y, uz = q.z - p.z;
  const double vx = r.x - p.x, vy = r.y - p.y, vz = r.z - p.z;
  const double det = ux * vy - uy * vx;
  Plane pl{0, 0, 0};
  if (det == 0.0) {
    pl.c = (p.z + q.z + r.z) / 3.0;
    return pl;
  }
  pl.a = (uz * vy - uy * vz) / det;
  pl.b = (ux * vz - uz * vx) / det;
  pl.c = p.z - pl.a * p.x - pl.b * p.y;
  return pl;
}

// Integral of |d| over a triangle where d is linear with corner values d0, d1, d2.
double abs_integral(double area, double d0, double d1, double d2) {
  const double mean = (d0 + d1 + d2) / 3.0;
  // Sort so that the corner whose sign differs from the other two is d0 (if any).
  const bool p0 = d0 > 0, p1 = d1 > 0, p2 = d2 > 0;
  if (p0 == p1 && p1 == p2) return area * std::fabs(mean);
  double lone, o1, o2;
  if (p1 == p2) {
    lone = d0, o1 = d1, o2 = d2;
  } else if (p0 == p2) {
    lone = d1, o1 = d0, o2 = d2;
  } else {
    lone = d2, o1 = d0, o2 = d1;
  }
  // The sub-triangle at the lone corner where d has the lone sign: its share of the area is
  // t1 * t2, and d averages lone / 3 over it.
  const double t1 = lone / (lone - o1);
  const double t2 = lone / (lone - o2);
  const double part = area * t1 * t2 * lone / 3.0;  // signed integral over that sub-triangle
  // |d| integral = 2 * |part| - sign(lone) * (integral of d), written without branches on sign
  return 2.0 * std::fabs(part) - (lone > 0 ? 1.0 : -1.0) * area * mean;
}

// A convex polygon of at most 5 vertices: a triangle clipped by two half-planes.
struct SmallPoly {
  P2 v[8];
  int n = 0;
};

// Clips a convex polygon to the half-plane left of (or on) the directed line a -> b.
// note: inlined into vp_volume_exact's loop (two calls a pair of triangles), where a call
// copied the polygons through memory.
[[gnu::always_inline]] inline void clip_left(const SmallPoly& in, P2 a, P2 b, SmallPoly& out) {
  out.n = 0;
  double sp = cross(a, b, in.v[0]);
  for (int i = 0; i < in.n; ++i) {
    const P2 p = in.v[i], q = in.v[i + 1 == in.n ? 0 : i + 1];
    const double sq = cross(a, b, q);
    if (sp >= 0) out.v[out.n++] = p;
    if ((sp > 0 && sq < 0) || (sp < 0 && sq > 0)) {
      const double t = sp / (sp - sq);
      out.v[out.n++] = {p.x + t * (q.x - p.x), p.y + t * (q.y - p.y)};
    }
    sp = sq;
  }
}

double triangle_area(P2 a, P2 b, P2 c) { return 0.5 * cross(a, b, c); }

std::size_t fan_count(const Star& s) { return s.closed ? s.n : s.n - 1; }

// Height of the surface `tris` (over points pts) at (x, y), or NaN when outside all.
double height_in(const std::vector<std::array<const Point3*, 3>>& tris, double x, double y) {
  for (const auto& t : tris) {
    const P2 a{t[0]->x, t[0]->y}, b{t[1]->x, t[1]->y}, c{t[2]->x, t[2]->y}, p{x, y};
    const double area = cross(a, b, c);
    if (area <= 0) continue;
    const double l0 = cross(b, c, p), l1 = cross(c, a, p), l2 = cross(a, b, p);
    if (l0 >= 0 && l1 >= 0 && l2 >= 0) {
      return (l0 * t[0]->z + l1 * t[1]->z + l2 * t[2]->z) / area;
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

double vp_volume_exact(const Star& s, const std::vector<LinkTriangle>& after) {
  const P2 apex{s.apex.x, s.apex.y};
  const std::size_t wedges = fan_count(s);
  // A new triangle that does not contain the apex lies within the arc between its corners
  // seen from the apex, which prunes most wedges. note: for link vertices in counter-
  // clockwise order, the arc from link[i] to link[j] exceeds pi exactly when
  // (link[i] - apex) x (link[j] - apex) < 0.
  auto reflex = [&](int i, int j) {
    const double ax = s.link[i].x - apex.x, ay = s.link[i].y - apex.y;
    const double bx = s.link[j].x - apex.x, by = s.link[j].y - apex.y;
    return ax * by - ay * bx < 0;
  };
  SmallPoly poly, tmp;
  double volume = 0.0;
  // The fan triangles' planes, each made once, first, for the stars of at most kCached link
  // vertices (nearly all), where each was made again for every new triangle it met. note:
  // every wedge meets a new triangle (they tile the same polygon), so none is made in vain;
  // made on first use, its test's branch missed often (cachegrind).
  constexpr std::size_t kCached = 32;
  Plane before[kCached];
  const std::size_t cached = std::min(wedges, kCached);
  for (std::size_t i = 0; i < cached; ++i) {
    before[i] = plane_through(s.apex, s.link[i], s.link[link_next(i, s.n)]);
  }
  // Each new triangle is cut by the wedges of the fan (apex, link[i], link[i+1]); inside one
  // piece both surfaces are planes, so their difference is linear and integrates exactly.
  for (const LinkTriangle& t : after) {
    const Point3 &p = s.link[t[0]], &q = s.link[t[1]], &r = s.link[t[2]];
    const Plane after_plane = plane_through(p, q, r);
    std::array<int, 3> k = t;
    std::sort(k.begin(), k.end());
    // Wedges [first, first + count) (mod n) may meet the triangle.
    std::size_t first = 0, count = wedges;
    if (!s.closed || reflex(k[2], k[0])) {
      first = k[0], count = k[2] - k[0];
    } else if (reflex(k[0], k[1])) {
      first = k[1], count = s.n - (k[1] - k[0]);
    } else if (reflex(k[1], k[2])) {
      first = k[2], count = s.n - (k[2] - k[1]);
    }
    for (std::size_t w = 0; w < count; ++w) {
      const std::size_t i = first + w < s.n ? first + w : first + w - s.n;  // both below n
      const Point3& a = s.link[i];
      const Point3& b = s.link[link_next(i, s.n)];
      const P2 pa{a.x, a.y}, pb{b.x, b.y};
      poly.n = 3;
      poly.v[0] = {p.x, p.y}, poly.v[1] = {q.x, q.y}, poly.v[2] = {r.x, r.y};
      // note: the new triangle lies inside the link polygon, so the wedge at the apex
      // between the rays to a and b cuts out exactly its part in fan triangle (apex, a, b).
      clip_left(poly, apex, pa, tmp);
      if (tmp.n < 3) continue;
      clip_left(tmp, pb, apex, poly);
      if (poly.n < 3) continue;
      const Plane before_plane = i < cached ? before[i] : plane_through(s.apex, a, b);
      auto diff = [&](P2 v) { return before_plane.at(v.x, v.y) - after_plane.at(v.x, v.y); };
      const double d0 = diff(poly.v[0]);
      double d_prev = diff(poly.v[1]);
      for (int m = 2; m < poly.n; ++m) {
        const double d_next = diff(poly.v[m]);
        const double area = triangle_area(poly.v[0], poly.v[m - 1], poly.v[m]);
        if (area > 0) volume += abs_integral(area, d0, d_prev, d_next);
        d_prev = d_next;
      }
    }
  }
  return volume;
}

double vp_volume_bound(const Star& s, const std::vector<LinkTriangle>& after) {
  // Heights relative to the apex: the difference of the surfaces is the same, and the sums
  // stay on the scale of the local relief.
  const double z0 = s.apex.z;
  const P2 apex{s.apex.x, s.apex.y};
  double before = 0.0, relief = 0.0;
  for (std::size_t i = 0; i < fan_count(s); ++i) {
    const Point3& a = s.link[i];
    const Point3& b = s.link[link_next(i, s.n)];
    before += triangle_area(apex, {a.x, a.y}, {b.x, b.y}) * ((a.z - z0) + (b.z - z0));
  }
  double after_sum = 0.0, area = 0.0;
  for (const LinkTriangle& t : after) {
    const Point3 &p = s.link[t[0]], &q = s.link[t[1]], &r = s.link[t[2]];
    const double a = triangle_area({p.x, p.y}, {q.x, q.y}, {r.x, r.y});
    after_sum += a * ((p.z - z0) + (q.z - z0) + (r.z - z0));
    area += std::fabs(a);
  }
  for (std::size_t i = 0; i < s.n; ++i) relief = std::max(relief, std::fabs(s.link[i].z - z0));
  const double bound = std::fabs(before - after_sum) / 3.0;
  // The margin: vp_volume_exact works with absolute heights (planes through them), whose
  // rounding is about 1e-16 x |z| x area a term; 1e-10 is far above it for any stars here.
  const double margin = 1e-10 * area * (std::fabs(z0) + relief) + 1e-9 * bound;
  return std::max(0.0, bound - margin);
}

double vp_volume_monte_carlo(const Star& s, const std::vector<LinkTriangle>& after, int samples,
                             std::uint64_t seed) {
  std::vector<std::array<const Point3*, 3>> before_tris, after_tris;
  for (std::size_t i = 0; i < fan_count(s); ++i) {
    before_tris.push_back({&s.apex, &s.link[i], &s.link[(i + 1) % s.n]});
  }
  for (const LinkTriangle& t : after)
    after_tris.push_back({&s.link[t[0]], &s.link[t[1]], &s.link[t[2]]});
  // The box B bounds both surfaces over the bounding rectangle of the affected vertices.
  double x0 = s.apex.x, x1 = s.apex.x, y0 = s.apex.y, y1 = s.apex.y, z0 = s.apex.z, z1 = s.apex.z;
  for (std::size_t i = 0; i < s.n; ++i) {
    x0 = std::min(x0, s.link[i].x), x1 = std::max(x1, s.link[i].x);
    y0 = std::min(y0, s.link[i].y), y1 = std::max(y1, s.link[i].y);
    z0 = std::min(z0, s.link[i].z), z1 = std::max(z1, s.link[i].z);
  }
  const double box = (x1 - x0) * (y1 - y0) * (z1 - z0);
  if (box <= 0 || samples <= 0) return 0.0;
  SplitMix rng{seed};
  int between = 0;
  for (int k = 0; k < samples; ++k) {
    const double x = x0 + rng.uniform() * (x1 - x0);
    const double y = y0 + rng.uniform() * (y1 - y0);
    const double z = z0 + rng.uniform() * (z1 - z0);
    const double a = height_in(before_tris, x, y);
    if (std::isnan(a)) continue;  // outside the star: both surfaces agree there
    const double b = height_in(after_tris, x, y);
    if (std::isnan(b)) continue;
    if ((a < z && z < b) || (b < z && z < a)) ++between;
  }
  return box * between / samples;
}

namespace {

double dist3(const Point3& a, const Point3& b) {
  return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) +
                   (a.z - b.z) * (a.z - b.z));
}

// The shortest paths over the fan from link[from], going counter-clockwise (dir = +1) or
// clockwise (dir = -1), to the link vertex reached after k fan triangles, for k = 1 to
// max_steps, into gd[k]: the fan unfolded into the plane around the apex (at the origin); where
// the unfolded angle is pi or more the path runs through the apex; otherwise it is the taut
// string from one end to the other, bent round the link vertices that poke towards the apex
// (a convex chain). The chain is kept as the unfolding goes (a point is taken in as the string's
// end, the vertices it no longer wraps round dropped), with its length so far at each of its
// vertices: each k reads its string off the chain, every pair from one start in one pass.
// note: unfolded by rotations (each fan triangle's apex angle as its cosine and sine), not by
// the cosine and sine of the summed angles: no trigonometry, which took 30 % of pld's time
// (2026-11-28: rounding apart, the same paths).
void fan_geodesics(const Star& s, const std::vector<double>& radius, const std::vector<P2>& turn,
                   std::size_t from, std::size_t max_steps, int dir, std::vector<P2>& chain,
                   std::vector<double>& length, std::vector<double>& gd) {
  chain.resize(max_steps + 1);
  length.resize(max_steps + 1);
  gd.resize(max_steps + 1);
  chain[0] = {radius[from], 0.0};
  length[0] = 0.0;
  std::size_t h = 1;          // the chain's vertices
  double cx = 1.0, cy = 0.0;  // the unfolded direction
  bool past_pi = false;
  std::size_t idx = from;
  for (std::size_t k = 1; k <= max_steps; ++k) {
    const P2 t = turn[dir > 0 ? idx : link_prev(idx, s.n)];
    idx = dir > 0 ? link_next(idx, s.n) : link_prev(idx, s.n);
    // note: each turn is by an angle in [0, pi], so while the sum is below pi the direction
    // stays in the upper half plane; the sum reaches pi where it leaves it (or lands on -x).
    // The angles are not negative: from then on every path runs through the apex.
    if (!past_pi) {
      const double nx = cx * t.x - cy * t.y, ny = cx * t.y + cy * t.x;
      cx = nx;
      cy = ny;
      past_pi = ny < 0 || (ny == 0 && nx < 0);
    }
    if (past_pi) {
      gd[k] = radius[from] + radius[idx];
      continue;
    }
    const P2 p{radius[idx] * cx, radius[idx] * cy};
    // Keep only right turns: those are the link vertices the string wraps round.
    while (h >= 2 && cross(chain[h - 2], chain[h - 1], p) >= 0) --h;
    // note: not std::hypot, several times slower; the lengths are far from overflow.
    const double dx = p.x - chain[h - 1].x, dy = p.y - chain[h - 1].y;
    length[h] = length[h - 1] + std::sqrt(dx * dx + dy * dy);
    chain[h++] = p;
    gd[k] = length[h - 1];
  }
}

}  // namespace

double pld_importance(const Star& s) {
  const std::size_t n = s.n;
  // note: per thread, not per call (an evaluation is a few microseconds; allocating took 5 %).
  thread_local std::vector<double> radius;
  thread_local std::vector<P2> turn, chain;
  thread_local std::vector<double> length, ccw, cw;
  radius.assign(n, 0.0);
  turn.assign(n, P2{1.0, 0.0});
  for (std::size_t i = 0; i < n; ++i) radius[i] = dist3(s.apex, s.link[i]);
  // The 3D angle at the apex of each fan triangle, as its cosine and sine (not negative).
  for (std::size_t i = 0; i < fan_count(s); ++i) {
    const Point3& a = s.link[i];
    const Point3& b = s.link[link_next(i, n)];
    const double ax = a.x - s.apex.x, ay = a.y - s.apex.y, az = a.z - s.apex.z;
    const double bx = b.x - s.apex.x, by = b.y - s.apex.y, bz = b.z - s.apex.z;
    const double cx = ay * bz - az * by, cy = az * bx - ax * bz, cz = ax * by - ay * bx;
    const double sine = std::sqrt(cx * cx + cy * cy + cz * cz),
                 cosine = ax * bx + ay * by + az * bz;
    const double norm = std::sqrt(sine * sine + cosine * cosine);
    // note: a degenerate triangle (an edge of length 0: no TIN of distinct vertices has one)
    // turns by nothing (atan2 of two zeros gave 0 or pi by their signs).
    if (norm > 0) turn[i] = {cosine / norm, sine / norm};
  }
  double ratio = 1.0;
  for (std::size_t i = 0; i + 2 < n; ++i) {
    // Pairs (i, j > i + 1): j - i steps counter-clockwise, n - (j - i) clockwise.
    fan_geodesics(s, radius, turn, i, n - 1 - i, +1, chain, length, ccw);
    if (s.closed) fan_geodesics(s, radius, turn, i, n - 2, -1, chain, length, cw);
    for (std::size_t j = i + 2; j < n; ++j) {
      if (s.closed && i == 0 && j == n - 1) continue;  // joined by a link edge
      const double ed = dist3(s.link[i], s.link[j]);
      double gd = ccw[j - i];
      if (s.closed) gd = std::min(gd, cw[n - (j - i)]);
      if (gd > 0) ratio = std::min(ratio, ed / gd);
    }
  }
  return 1.0 - ratio;
}

}  // namespace dpts::core

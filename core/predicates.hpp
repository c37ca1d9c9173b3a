// Geometric predicates for the kernels' hot loops, exact where they answer: an orientation
// filter and CGAL's perturbed in-circle test on a frame's lattice, both without CGAL.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>

namespace dpts::core {

// The sign of (b - a) x (p - a) (1: a, b, p counter-clockwise; -1: clockwise) where doubles
// settle it, by Shewchuk's a priori bound (orient2d's ccwerrboundA: "Adaptive Precision
// Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997); 0 where the sign is
// in doubt (a caller then asks an exact test, CGAL's). note: CGAL's own static filter orders
// the differences' magnitudes with branches, which missed often in vp's refill and qem's fold
// test (cachegrind's branch simulation).
inline int orientation_filtered(double ax, double ay, double bx, double by, double px, double py) {
  const double l = (bx - ax) * (py - ay);
  const double r = (by - ay) * (px - ax);
  const double det = l - r;
  constexpr double kEpsilon = 0x1p-53;
  constexpr double kBound = (3 + 16 * kEpsilon) * kEpsilon;
  const double bound = kBound * (std::abs(l) + std::abs(r));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return 0;
}

// Whether p lies inside the circle through a, b, c (counter-clockwise) by CGAL's perturbed
// test (Triangulation_2::side_of_oriented_circle with perturb; a point on the circle is inside
// or not as a symbolic perturbation decides), computed exactly where every coordinate lies on
// the lattice of 2^-24 (a frame's points do: GridFrame::from_jacobian) and a, b, c lie within
// 64 units of p: the differences from p in units of 2^-24 then take 31 bits, the determinant's
// terms 122, in 128-bit integers. Gives 1 (inside), 0 (not), or -1 (nothing known) where a
// point is off the lattice or too far.
// note: a grid's squares are cocircular, so a test in doubles leaves many signs in doubt;
// CGAL's own (an interval filter, then multiprecision) took 8 % of vp's samples.
inline int lattice_in_circle(double ax, double ay, double bx, double by, double cx, double cy,
                             double px, double py) {
  const double v[8] = {ax, ay, bx, by, cx, cy, px, py};
  std::int64_t k[8];
  for (int i = 0; i < 8; ++i) {
    const double scaled = v[i] * 0x1p24;
    if (!(std::fabs(scaled) < 0x1p52)) return -1;
    k[i] = static_cast<std::int64_t>(scaled);
    if (static_cast<double>(k[i]) != scaled) return -1;
  }
  std::int64_t d[6];
  for (int i = 0; i < 6; ++i) {
    d[i] = k[i] - k[6 + (i & 1)];
    if (d[i] >= (std::int64_t{1} << 30) || d[i] <= -(std::int64_t{1} << 30)) return -1;
  }
  const std::int64_t adx = d[0], ady = d[1], bdx = d[2], bdy = d[3], cdx = d[4], cdy = d[5];
  // Each below 2^61 in magnitude. bc, ca and ab are also the orientations of (p, b, c),
  // (a, p, c) and (a, b, p).
  const std::int64_t bc = bdx * cdy - cdx * bdy, ca = cdx * ady - adx * cdy;
  const std::int64_t ab = adx * bdy - bdx * ady;
  const std::int64_t al = adx * adx + ady * ady, bl = bdx * bdx + bdy * bdy;
  const std::int64_t cl = cdx * cdx + cdy * cdy;
  __extension__ using Int128 = __int128;  // GCC's and Clang's
  const Int128 det = Int128{al} * bc + Int128{bl} * ca + Int128{cl} * ab;
  if (det != 0) return det > 0 ? 1 : 0;
  // On the circle: the symbolic perturbation (Devillers and Teillaud, 2003) as CGAL makes it:
  // the points in xy order, from the greatest, until one's minor is not zero; p's own means
  // outside.
  int order[4] = {0, 1, 2, 3};  // a, b, c, p
  auto less_xy = [&](int x, int y) {
    return k[2 * x] < k[2 * y] || (k[2 * x] == k[2 * y] && k[2 * x + 1] < k[2 * y + 1]);
  };
  for (int i = 1; i < 4; ++i) {
    for (int j = i; j > 0 && less_xy(order[j], order[j - 1]); --j) {
      std::swap(order[j], order[j - 1]);
    }
  }
  const std::int64_t minor[3] = {bc, ca, ab};  // the sign where a, b or c is perturbed
  for (int i = 3; i > 0; --i) {
    if (order[i] == 3) return 0;
    if (minor[order[i]] != 0) return minor[order[i]] > 0 ? 1 : 0;
  }
  return 0;
}

}  // namespace dpts::core

// Vertex importance for the elimination method: VP (volume preserving) and PLD (preserving
// local distances), after "Distance Preserving Terrain Simplification: An
// Experimental Study", sections 4.1 and 4.2. Pure geometry on a vertex star; no CGAL.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dpts::core {

// A point in metres (x, y in the planar frame, z = height).
struct Point3 {
  double x = 0, y = 0, z = 0;
};

// The star of a vertex: the apex and its link in counter-clockwise order. A closed star
// has the fan triangles (apex, link[i], link[i+1 mod n]); an open star (a vertex on the
// outline of the footprint, whose link[0], apex, link[n-1] are collinear) has the triangles
// for i = 0 .. n-2 only.
struct Star {
  Point3 apex;
  const Point3* link = nullptr;
  std::size_t n = 0;
  bool closed = true;
};

// The index after and before i round a link (or any ring) of n (i < n). note: not % n, a
// 64-bit division: the refill's and the importances' loops waited on one an element.
inline std::size_t link_next(std::size_t i, std::size_t n) { return i + 1 == n ? 0 : i + 1; }
inline std::size_t link_prev(std::size_t i, std::size_t n) { return i == 0 ? n - 1 : i - 1; }

// A triangle of the star's polygon after the apex is removed, as indices into link,
// counter-clockwise.
using LinkTriangle = std::array<int, 3>;

// VP, exact: the volume (m^3) of the set of points between the star's surface and the
// surface of `after` (the retriangulation of the polygon of the link), i.e. the integral of
// |z_before - z_after| over the polygon. Computed on the overlay of the two triangulations.
double vp_volume_exact(const Star& star, const std::vector<LinkTriangle>& after);

// A lower bound of vp_volume_exact(star, after) that needs no overlay: |integral of
// (z_before - z_after)| over the polygon (<= the integral of its absolute value), less a margin
// for rounding in either computation. Equal to the exact volume, but for that margin, where one
// surface lies wholly above the other.
double vp_volume_bound(const Star& star, const std::vector<LinkTriangle>& after);

// VP, the paper's Monte Carlo estimate: `samples` points uniform in the box bounding both
// surfaces over the link's bounding rectangle; volume = box volume * share of the points that
// lie between the two surfaces. `seed` fixes the points (deterministic).
double vp_volume_monte_carlo(const Star& star, const std::vector<LinkTriangle>& after, int samples,
                             std::uint64_t seed);

// PLD: 1 - min over pairs of link vertices (v, w) of ED(v, w) / GD(v, w), in [0, 1]. ED is
// the 3D Euclidean distance; GD is the exact geodesic distance between v and w restricted
// to the star (the shortest path over the fan triangles, either way round a closed star),
// computed by unfolding the fan into the plane. Neighbours joined by a link edge have
// ED = GD and do not count.
double pld_importance(const Star& star);

}  // namespace dpts::core

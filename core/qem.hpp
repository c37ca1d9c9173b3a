// dpts's own quadric edge collapse (`--algo qem`): Garland and Heckbert's greedy collapse with
// triangle quadrics, a cost that also sees the change of surface area, a footprint kept
// exactly (the outline's straight runs may thin out, its corners never move), no folds seen
// from above, and vertices that may be locked (the seams between pieces of the piece engine).
//
// Written for terrain meshes: a compact indexed half-edge structure (three vertex ids and
// three opposite half-edges per face), no per-collapse allocation, and the stars walked in
// place. It replaced a CGAL EdgeCollapse version of the same rules (same errors, a quarter of
// the time: docs/results.md); --algo qslim (the paper's competitor, core/qslim.hpp) keeps
// CGAL's.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "core/elimination.hpp"
#include "core/steiner_graph.hpp"

namespace dpts::core {

// A quadric error form: x^T A x + 2 b.x + c, A symmetric (a00 a01 a02 a11 a12 a22).
struct Quadric {
  double a00 = 0, a01 = 0, a02 = 0, a11 = 0, a12 = 0, a22 = 0, b0 = 0, b1 = 0, b2 = 0, c = 0;
  // The squared distance to the plane n.x + d = 0, times |n|^2.
  static Quadric plane(const double n[3], double d);
  Quadric& operator+=(const Quadric& q);
  Quadric& operator*=(double w);
  // The form at x. note: inline, called from every plan of qem's collapse (about 13M on San
  // Gabriel to 10 %).
  double operator()(const double x[3]) const {
    const double ax = a00 * x[0] + a01 * x[1] + a02 * x[2];
    const double ay = a01 * x[0] + a11 * x[1] + a12 * x[2];
    const double az = a02 * x[0] + a12 * x[1] + a22 * x[2];
    return x[0] * ax + x[1] * ay + x[2] * az + 2 * (b0 * x[0] + b1 * x[1] + b2 * x[2]) + c;
  }
};

struct QemOptions {
  // Weight of the squared change of the collapse's star 3D surface area, added to the quadric
  // cost: a collapse that flattens or roughens the surface costs more. 0: the quadric's cost
  // alone (Garland and Heckbert's).
  double area_weight = 100.0;
  // The starting quadrics (when `quadrics` is empty): each face's plane at unit weight
  // (Garland and Heckbert's plane quadrics, as CGAL's GarlandHeckbert_plane_policies), instead
  // of weighted by the triangle's squared doubled area.
  bool plane_quadrics = false;
  // Weight of an outline edge's quadric (the plane through it perpendicular to its face; CGAL's
  // discontinuity multiplier).
  double outline_weight = 1.0;
  // Every outline vertex locked (after the starting quadrics are made): the outline never
  // changes, and an edge between two outline vertices is never collapsed.
  bool lock_outline = false;
  // Per vertex: locked vertices never go and never move (a neighbour may collapse onto one).
  // Border edges between two locked vertices get no outline quadric (they are seams, not
  // outline). Empty: none.
  std::vector<char> locked;
  // Per vertex: frozen vertices never go, never move, and no neighbour collapses onto one
  // (their quadric may be partial: the piece engine's seams with pieces outside a pre-merge).
  // Empty: none.
  std::vector<char> frozen;
  // Per half-edge of the mesh (face f's k-th, from corner k to corner k + 1 mod 3, is 3 f + k):
  // the other face's half-edge on its edge, or 0xFFFFFFFF on the outline (grid_tin's, for a
  // grid TIN). Checked to pair half-edges of opposite direction. Empty: found from the faces.
  std::vector<std::uint32_t> opposites;
  // Per vertex: the starting quadrics (a piece engine's merge carries them on). Empty: each
  // vertex gets the triangle quadrics of its faces and the plane quadrics of its outline edges.
  std::vector<Quadric> quadrics;
  // Whether outline vertex v lies on a straight run from its outline neighbour a to b (input
  // ids); null: a, v, b exactly collinear in x, y. (A reprojected DEM's mesh is in true
  // output coordinates, where grid lines bend: its caller tests the grid instead.)
  std::function<bool(std::uint32_t a, std::uint32_t v, std::uint32_t b)> outline_collinear;
  // Whether the outline may run straight from vertex a to vertex b (input ids); null: always.
  std::function<bool(std::uint32_t a, std::uint32_t b)> outline_chord_ok;
  // Whether a triangle (corners a, b, c, counter-clockwise seen from above; x, y in the second
  // plane when there is one, below) may be made; null: always (--max-error's test).
  std::function<bool(const double* a, const double* b, const double* c)> triangle_ok;
  // A second plane the positions map to, where new triangles must be counter-clockwise too:
  // a reprojected DEM's grid (in frame units). Its mesh is in true output coordinates, where
  // grid lines bend, and a sliver along a straight outline run can be counter-clockwise there
  // but degenerate on the grid, over a void's cell (pyrenees_andorra_voids to 10 %).
  // plane_xy: per vertex x, y in the plane (empty: no second plane). to_plane: maps a new
  // position (a collapse's optimum) there; false if it cannot (the collapse is refused).
  std::vector<double> plane_xy;
  std::function<bool(const double* xyz, double* xy)> to_plane;
  // Runs fn(begin, end) over parts of [0, n), in any order, maybe on several threads at once:
  // the first costs of every edge (the piece engine's merge, one large mesh), which read the
  // mesh only. The callbacks above must then be safe to call from several threads. Null: in
  // order, on the calling thread. The result does not depend on it.
  std::function<void(std::size_t n, const std::function<void(std::size_t, std::size_t)>& fn)>
      for_ranges;
  // With for_ranges: the interior edges of the least first costs (full_first_costs x the
  // collapses to make) also get their full cost (the area term's star walks) there, which
  // the collapse loop takes instead of walking for it where neither end's star has changed
  // since. 0: none. The same collapses either way; it pays where for_ranges runs on several
  // threads (the merge's loop is serial).
  std::size_t full_first_costs = 0;
};

struct QemResult {
  TriMesh mesh;                       // compacted, faces counter-clockwise
  std::vector<std::uint32_t> source;  // per output vertex: its input vertex id
  std::vector<Quadric> quadrics;      // per output vertex: its accumulated quadric
  std::vector<double> plane_xy;       // per output vertex: x, y in options.plane_xy's plane
  std::size_t input_vertices = 0, collapses = 0;
  std::size_t refused = 0;  // collapses refused at the top of the queue (fold, topology, bound)
  std::size_t full_costs_taken = 0;  // full costs made ahead (QemOptions::full_first_costs) used
};

// Simplifies a height-field mesh (faces counter-clockwise seen from above; an edge has at most
// two faces) by quadric edge collapse until at most `keep` vertices are left or no collapse
// is allowed (none costing more than max_cost). Throws std::invalid_argument on a non-manifold
// edge, Cancelled when progress returns false. The mesh and options are taken by value: move them
// in to save their memory while it runs.
QemResult qem_simplify(TriMesh mesh, std::size_t keep, QemOptions options = {},
                       const Progress& progress = nullptr,
                       double max_cost = std::numeric_limits<double>::infinity());

// qem_simplify in steps, for a caller that bounds the collapse's cost from several meshes'
// queues (the piece engine's pre-merge) or by a cost found beforehand (its pieces): the mesh
// prepared with every edge's first cost queued, then collapsed. Progress as qem_simplify's,
// each collapse() call counting from 0 to 1; the same rules and errors.
class QemCollapse {
 public:
  QemCollapse(TriMesh mesh, QemOptions options, Progress progress = nullptr);
  ~QemCollapse();
  QemCollapse(QemCollapse&&) noexcept;
  QemCollapse& operator=(QemCollapse&&) noexcept;
  // A copy, to go on from where this one is: the same collapses as this one would make. Its
  // options' tests and its progress are copies (what they point at must outlive both).
  QemCollapse(const QemCollapse& other);
  // Vertices left (at first: those of the mesh on some face).
  std::size_t vertices() const;
  // The most a collapse of the last collapse() call cost (0: it made none). Costs rise as
  // collapses go on, but not strictly (a collapse may lower its neighbours').
  double max_cost_made() const;
  // The queued edges' costs, lower bounds of what each collapse would cost now, appended.
  void queued_costs(std::vector<float>& out) const;
  // Collapses in cost order while more than keep vertices are left and the cheapest collapse
  // costs at most max_cost; returns how many it made. May be called again.
  std::size_t collapse(std::size_t keep, double max_cost);
  // The result, as qem_simplify's (every collapse so far counted). Once, last.
  QemResult result();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  QemResult r_;
};

}  // namespace dpts::core

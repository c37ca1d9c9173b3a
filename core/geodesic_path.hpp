// Exact geodesic lengths from Steiner-graph paths: the path's strip of faces is unfolded into
// the plane and the path pulled taut inside it (the funnel algorithm: Lee and Preparata,
// "Euclidean shortest paths in the presence of rectilinear barriers", Networks 14, 1984;
// Hershberger and Snoeyink, "Computing minimum length paths of a given homotopy class", CGTA 4,
// 1994), then, wherever the taut path bends around a mesh vertex whose other side is shorter
// (angle below pi), the strip is rerouted through that side and pulled taut again, until no
// such vertex is left: a locally shortest path, which is exact (Xin and Wang, "Efficiently
// determining a locally exact shortest path on polyhedral surfaces", Computer-Aided Design 39,
// 2007). Started from a Steiner path within about 1 % of the shortest, it is the geodesic.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/steiner_graph.hpp"

namespace dpts::core {

// A straightened path seen from above, for trying the same pair on another mesh, from source
// to target, neither end included: the mesh vertices it bends at, in order (empty: straight);
// and the taut path itself, where it crosses the edges of its strip of faces, thinned to the
// points it cannot do without (the rest within 5 % of the graph's delta of it), bends
// included.
struct PathRoute {
  std::vector<std::array<double, 2>> bends, taut;
};

// Per-thread scratch for straightening the paths of one SteinerGraph (read-only, shared).
class PathStraightener {
 public:
  explicit PathStraightener(const SteinerGraph& graph) : g_(graph) {}

  // The length of the locally shortest surface path from source to target that starts in the
  // homotopy class of the Steiner path through `nodes` (GeodesicQuery::path). Never longer than
  // the Steiner path when it succeeds; a real path on the mesh, so never shorter than the exact
  // geodesic. A path through a vertex from one of its fans to another (faces that meet at the
  // vertex alone) is cut there, each part straightened on its own. Returns a negative value
  // when the path's strip cannot be unfolded (a degenerate face, an edge of more than two
  // faces): the caller keeps the Steiner length then.
  double length(const SurfacePoint& source, const std::vector<std::uint32_t>& nodes,
                const SurfacePoint& target);

  // The shortest of the straightened paths the last search of `query` found to its target
  // `target` (at `target_point`): the path it settled the target through, and those through
  // every other node of the target's face (where the search's cut locus, two routes of nearly
  // equal length around some hill, passes by the target, its boundary nodes are reached by
  // both; the graph's error may have ranked the longer first; a path that joins one tried
  // already a few nodes back from the target's face is not tried). Infinity where the target
  // was not reached; the Steiner distance where no path could be straightened.
  // With route, the shortest one's route into it (both empty where none was straightened),
  // for along() and follow() on another mesh.
  double shortest(const GeodesicQuery& query, const SurfacePoint& source, std::size_t target,
                  const SurfacePoint& target_point, double steiner_distance,
                  PathRoute* route = nullptr);

  // The length of the locally shortest path from source to target that starts along `route`
  // (points seen from above, in order from source to target, such as another mesh's path
  // between the same points): the graph node nearest each crossing of the route with an edge,
  // straightened as in length(). Negative where the route leaves the mesh or does not end in
  // the target's face. With bends, the straightened path's route into it (as shortest()).
  double along(const SurfacePoint& source, const std::vector<std::array<double, 2>>& route,
               const SurfacePoint& target, PathRoute* bends = nullptr);

  // The same from the strip of the faces the route crosses (seen from above), not from the
  // graph nodes nearest its crossings: for a dense route (PathRoute::taut), whose way past
  // every vertex near it the strip keeps. (A route told by its bends alone is straight between
  // them from above, which a path on steep ground is not: along() it may pass a vertex on the
  // other side, and find a shorter path nearby where the meshes differ.)
  // With taut, the straightened path's route into it (as shortest()).
  double follow(const SurfacePoint& source, const std::vector<std::array<double, 2>>& route,
                const SurfacePoint& target, PathRoute* taut = nullptr);

  // What the calls so far did: paths straightened, strips pulled taut (one per pass), vertices
  // rerouted around, and paths that could not be straightened.
  struct Stats {
    std::size_t paths = 0, passes = 0, reroutes = 0, failed = 0;
  };
  const Stats& stats() const { return stats_; }

 private:
  struct Point2 {
    double x, y;
  };
  // A portal of the unfolded strip: the edge between face j - 1 and face j, its end on the
  // left and on the right of the direction of travel (mesh vertices and their plane positions).
  struct Portal {
    std::uint32_t left, right;
    Point2 l, r;
  };
  // A vertex the taut path bends at: the portal (1..faces - 1) whose end it is, and the
  // portals the funnel had read when it fixed the bend (it depends on no later one).
  struct Bend {
    std::uint32_t vertex;
    std::size_t portal, seen;
  };
  // A face of the strip unfolded: its corners and their plane positions.
  struct Unfolded {
    std::array<std::uint32_t, 3> ids;
    std::array<Point2, 3> p2;
  };
  // How face `face` unfolds after a face of corners `prev` (in that order): the corner of prev
  // off their shared edge (k) and its own (r), and r's offsets along and off the edge (len).
  struct Hinge {
    std::uint32_t face = 0xFFFFFFFFu;
    std::array<std::uint32_t, 3> prev{};
    std::uint32_t r = 0;
    int k = 0;
    double len = 0, along = 0, off = 0;
  };
  // The hinge cache's slot for face f.
  static std::size_t hinge_slot(std::uint32_t f) { return (f * 2654435761u) >> (32 - kHingeBits); }
  static constexpr int kHingeBits = 13;

  // Vertex v seen from above.
  std::array<double, 2> vertex_xy(std::uint32_t v) const;
  // The face around vertex v whose corner at v holds the direction to q, seen from above
  // (SteinerGraph::kNoFace: none, q beyond the outline there).
  std::uint32_t face_toward(std::uint32_t v, std::array<double, 2> q) const;
  // The edge of face f across which face g lies (-1: none).
  int edge_to(std::uint32_t f, std::uint32_t g) const;
  // The edge of face f, but `entry`, that segment p -> q leaves f through, seen from above (-1:
  // q is in f), with its corners' sides of the segment (orientations) in ta and tb.
  int exit_edge(std::uint32_t f, int entry, std::array<double, 2> p, std::array<double, 2> q,
                double& ta, double& tb) const;
  // The last taut path's route (from source to target), into route.
  void taut_route(PathRoute& route) const;
  // The last taut path's route appended to `cut` (a path cut at vertices between fans), then
  // `end` (the vertex it was cut at) if given.
  void append_part(PathRoute& cut, const SurfacePoint* end);
  // The strip of faces of the path from source through nodes[begin..] to target; false where
  // it cannot be made, with pinch the index of the node where the path passes between two fans
  // of a vertex (the strip then ends at it) and next_face the face it goes on in (pinch
  // kNoPinch: failed otherwise).
  bool build_strip(const SurfacePoint& source, const std::vector<std::uint32_t>& nodes,
                   std::size_t begin, const SurfacePoint& target, std::size_t& pinch,
                   std::uint32_t& next_face);
  static constexpr std::size_t kNoPinch = ~std::size_t{0};
  // The strip pulled taut from source to target and rerouted round vertices until locally
  // shortest (length() once the strip is built); negative where it cannot be unfolded.
  double pull_taut(const SurfacePoint& source, const SurfacePoint& target);
  void push_face(std::uint32_t f);
  bool walk_around(std::uint32_t v, std::uint32_t from, std::uint32_t to, bool shortest,
                   std::uint32_t avoid, std::vector<std::uint32_t>& fan) const;
  // The strip's portals from its face `from` on (0: all; else the faces before it are those
  // the last call unfolded); false where a face is degenerate.
  bool unfold(const SurfacePoint& source, const SurfacePoint& target, std::size_t from);
  // The taut path's length through the portals; the bends that read only portals before
  // `from` are kept from the last call (0: none).
  double funnel(std::size_t from);
  bool contains(std::uint32_t f, std::uint32_t v) const;
  double total_angle(std::uint32_t v, std::uint32_t f) const;
  double inside_angle(const Bend& b, std::size_t first, std::size_t last, Point2 prev,
                      Point2 next) const;

  const SteinerGraph& g_;
  std::vector<std::uint32_t> strip_, next_strip_, fan_;  // faces of the strip, in order
  std::vector<Portal> portals_;     // portals_[0] and back(): the source and the target
  std::vector<Unfolded> unfolded_;  // per face of the strip
  // note: the faces a pass unfolds are mostly those the last pass (or the last path from the
  // same source) did, after the same faces: their hinges, the arithmetic of the mesh's
  // coordinates, are kept by face (direct-mapped, 2^kHingeBits slots) and give the same bits.
  std::vector<Hinge> hinges_;
  std::vector<Point2> taut_;  // the taut path's points
  std::vector<Bend> bends_;
  std::vector<std::uint32_t> path_, around_, tried_, on_paths_;
  PathRoute part_;  // append_part's scratch
  Stats stats_;
  std::array<double, 2> source_xy_{}, target_xy_{};  // the last taut path's ends
  // The last path of length() or follow() cut at vertices between fans (split_): its parts'
  // routes and the vertices between them, which taut_route gives.
  bool split_ = false;
  PathRoute split_route_;
};

}  // namespace dpts::core

// Geodesic distances on a TIN approximated on the Steiner graph of "Distance Preserving Terrain
// Simplification" (the paper in ../shared/paper), section 2.1: floor(len(e)/delta) points inside
// every edge e, and inside every triangle a straight segment between every pair of points on its
// boundary (corners included). The graph is implicit: a triangle's clique is generated when
// Dijkstra reaches it, so memory is linear in the number of Steiner points.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

#include "core/huge_pages.hpp"
#include "core/mesh.hpp"

namespace dpts::core {

// Mean 3D length of the mesh's edges (each undirected edge once).
double mean_edge_length(const TriMesh& mesh);

// Renumbers the mesh's vertices in the Z order of their positions seen from above (ties by
// their old numbers), the faces following them (each keeps its place and its corners' order):
// the same surface, whose Steiner graph's searches then read the records of a face's corners
// near each other in memory, as they do its edges' (a DEM's grid TIN comes row by row).
void order_vertices_spatially(TriMesh& mesh);

// A point on a mesh: position (z lifted onto the face) and the face it lies in.
struct SurfacePoint {
  double x = 0, y = 0, z = 0;
  std::uint32_t face = 0;
};

class SteinerGraph {
 public:
  // Most nodes a graph may have (node ids are 32-bit, and signed where Dijkstra stores them).
  static constexpr std::uint32_t kMaxNodes = 0x7FFFFFFFu;

  // Builds edges, face adjacency and Steiner point positions. Throws std::invalid_argument if
  // a face's vertex index is out of range, an edge has more than two faces, delta is not
  // positive, or the graph would have more than kMaxNodes nodes (checked before allocating).
  // The mesh must outlive the graph.
  SteinerGraph(const TriMesh& mesh, double delta);

  // The graph's nodes (exact) and memory (bytes, construction's peak included) for mesh and
  // delta, without building it: one sort of the face edges.
  struct Estimate {
    std::size_t nodes = 0, bytes = 0;
  };
  static Estimate estimate(const TriMesh& mesh, double delta);

  const TriMesh& mesh() const { return mesh_; }
  double delta() const { return delta_; }
  std::size_t node_count() const { return nodes_.size(); }
  std::size_t edge_count() const { return edges_.size(); }
  std::size_t steiner_count() const { return node_count() - mesh_.vertex_count(); }
  const double* position(std::uint32_t node) const { return nodes_[node].data(); }

  // Hints the cache about what for_each_neighbour(node) will read: Dijkstra calls it when it
  // first reaches a node, long before the node is settled.
  void prefetch_position(std::uint32_t node) const {
    __builtin_prefetch(&nodes_[node]);
    if (node >= nv_) __builtin_prefetch(&node_edge_[node - nv_]);
  }
  void prefetch(std::uint32_t node) const {
    __builtin_prefetch(&nodes_[node]);
    if (node >= nv_) {
      __builtin_prefetch(&edges_[edge_of(node)]);
    } else {
      __builtin_prefetch(&corners_[corner_first_[node]]);
    }
  }

  // Calls fn(v) for nodes that for_each_neighbour(node, ...) most likely relaxes (the first of
  // each contiguous run), so that a search can prefetch their records before it settles node.
  template <typename Fn>
  void for_each_neighbour_hint(std::uint32_t node, Fn&& fn) const {
    if (node < mesh_.vertex_count()) {
      for (std::uint32_t k = corner_first_[node]; k < corner_first_[node + 1]; ++k) {
        const Corner& c = corners_[k];
        fn(c.along[0]);
        if (c.across_first < c.across_end) fn(c.across_first);
      }
      return;
    }
    const Edge& e = edges_[edge_of(node)];
    for (const Edge::Side& side : e.sides) {
      if (side.face == kNoFace) continue;
      fn(side.opposite);
      // note: an empty run's first is no node of it (maybe one past the last node).
      if (side.first[0] < side.end[0]) fn(side.first[0]);
      if (side.first[1] < side.end[1]) fn(side.first[1]);
    }
  }

  // Bounds on the length of a graph edge (a segment between two nodes of one face): every one
  // is at least min_segment() and at most max_segment(). min_segment() is 0 when some face is
  // degenerate (a zero angle).
  double min_segment() const { return min_segment_; }
  double max_segment() const { return max_segment_; }

  // The nodes on face f's boundary (its corners and its edges' Steiner points), into out.
  void face_nodes(std::uint32_t f, std::vector<std::uint32_t>& out) const;
  // The nodes on face f's edge i, from corner i to corner i + 1 (both included), into out.
  void edge_nodes(std::uint32_t f, int i, std::vector<std::uint32_t>& out) const;

  // Topology, for following a path through the faces (see geodesic_path.hpp).
  // The face across face f's edge i (from corner i to corner i + 1), kNoFace on the outline.
  std::uint32_t across(std::uint32_t f, int i) const {
    const Edge& e = edges_[face_edges_[f][i]];
    return e.sides[0].face == f ? e.sides[1].face : e.sides[0].face;
  }
  // The mesh vertices a Steiner node's edge joins; for a vertex node, {node, node}.
  std::array<std::uint32_t, 2> node_edge_ends(std::uint32_t node) const {
    if (node < mesh_.vertex_count()) return {node, node};
    return edges_[edge_of(node)].ends;
  }
  // Where node v lies along Steiner node u's edge (v: one of its nodes or ends), as a fraction
  // of its length from its first end (the Steiner points are spaced evenly).
  double edge_fraction(std::uint32_t u, std::uint32_t v) const {
    const Edge& e = edges_[edge_of(u)];
    if (v == e.ends[0]) return 0.0;
    if (v == e.ends[1]) return 1.0;
    return static_cast<double>(v - e.first + 1) / static_cast<double>(e.end - e.first + 1);
  }
  // The corner of face f off a Steiner node's edge (f: one of the edge's faces).
  std::uint32_t opposite(std::uint32_t node, std::uint32_t f) const {
    const Edge& e = edges_[edge_of(node)];
    return e.sides[0].face == f ? e.sides[0].opposite : e.sides[1].opposite;
  }
  // The angle (3D) of face f at its corner v.
  double corner_angle(std::uint32_t f, std::uint32_t v) const;
  // The face across f's edge (v, x), kNoFace on the outline (or where (v, x) is not its edge).
  std::uint32_t across_edge(std::uint32_t f, std::uint32_t v, std::uint32_t x) const;
  // The corner of face f that is neither v nor x (kNoFace for x: f's first corner but v).
  std::uint32_t third_corner(std::uint32_t f, std::uint32_t v, std::uint32_t x) const {
    for (const std::uint32_t c : mesh_.faces[f]) {
      if (c != v && c != x) return c;
    }
    return kNoFace;
  }
  // A walk round vertex v from face f, leaving f across its edge (v, x): the sum of the corner
  // angles at v of the faces passed (f's included), how many, and whether it came back to f
  // (else it reached the outline, or passed kMaxFan faces).
  struct Fan {
    double angle = 0;
    std::uint32_t faces = 0;
    bool closed = false;
  };
  Fan walk_fan(std::uint32_t v, std::uint32_t f, std::uint32_t x) const;
  // Most faces a walk round one vertex passes.
  static constexpr int kMaxFan = 4096;
  // Keeps each vertex's total angle (vertex_angle), 8 bytes a vertex, for PathStraightener,
  // which otherwise walks round the vertex for every bend; plain searches do not need it.
  void keep_vertex_angles();
  // The sum of vertex v's corner angles where its faces form one closed fan; -1 on the outline;
  // NaN where its faces form several fans or more than kMaxFan, or where the angles are not
  // kept (then a walk from a face of the caller's own, walk_fan, answers).
  double vertex_angle(std::uint32_t v) const {
    return vertex_angle_.empty() ? std::numeric_limits<double>::quiet_NaN() : vertex_angle_[v];
  }
  // Calls fn(f) for each face around vertex v (in no particular order).
  template <typename Fn>
  void for_each_face_of_vertex(std::uint32_t v, Fn&& fn) const {
    for (std::uint32_t k = corner_first_[v]; k < corner_first_[v + 1]; ++k) fn(corners_[k].face);
  }

  // Where a node's distance label came from (Dijkstra records it with the label): a face id,
  // the node's own edge, or anywhere.
  static constexpr std::uint32_t kAlongEdge = 0xFFFFFFFEu;
  static constexpr std::uint32_t kAnywhere = 0xFFFFFFFFu;

  // The relaxations Dijkstra needs from a settled node, given where its label came from.
  // Calls node_fn(v, via) for nodes v joined to `node` by a graph edge, via the face the edge
  // lies in (kAlongEdge along the node's own edge), and face_fn(f) for the faces whose targets
  // the node must relax. Two exact prunings, both from the triangle inequality in one face
  // (every pair of a face's boundary points is joined, so for p, u, v on one face
  // |p v| <= |p u| + |u v|):
  // - Along the node's own edges only the nearest node on each side is given: the others lie on
  //   the same straight line, so the path through the nearest one has the same length.
  // - A node whose label came from p through face F skips F: p relaxed all of F (or its own
  //   predecessor did, by induction), never worse than through this node. A Steiner point so
  //   relaxes only the face across its edge; one reached along its edge from a neighbour q only
  //   continues along the edge (q covers both faces).
  // Distances are those of the full graph (up to rounding).
  template <typename NodeFn, typename FaceFn>
  void for_each_neighbour(std::uint32_t node, std::uint32_t entry, NodeFn&& node_fn,
                          FaceFn&& face_fn) const {
    const std::uint32_t nv = static_cast<std::uint32_t>(mesh_.vertex_count());
    auto range = [&](std::uint32_t first, std::uint32_t end, std::uint32_t via) {
      for (std::uint32_t n = first; n < end; ++n) node_fn(n, via);
    };
    if (node < nv) {
      for (std::uint32_t k = corner_first_[node]; k < corner_first_[node + 1]; ++k) {
        const Corner& c = corners_[k];
        if (c.face == entry) continue;
        node_fn(c.along[0], kAlongEdge);
        node_fn(c.along[1], kAlongEdge);
        range(c.across_first, c.across_end, c.face);
        face_fn(c.face);
      }
      return;
    }
    const Edge& e = edges_[edge_of(node)];
    if (entry == kAlongEdge || entry == kAnywhere) {
      node_fn(node == e.first ? e.ends[0] : node - 1, kAlongEdge);
      node_fn(node + 1 == e.end ? e.ends[1] : node + 1, kAlongEdge);
      if (entry == kAlongEdge) return;
    }
    for (const Edge::Side& side : e.sides) {
      if (side.face == kNoFace || side.face == entry) continue;
      node_fn(side.opposite, side.face);
      range(side.first[0], side.end[0], side.face);
      range(side.first[1], side.end[1], side.face);
      face_fn(side.face);
    }
  }
  static constexpr std::uint32_t kNoFace = 0xFFFFFFFFu;

 private:
  // The constructor's steps, in order.
  void build_nodes(const std::vector<std::tuple<std::uint64_t, std::uint32_t, int>>& face_edges,
                   std::size_t nodes, std::size_t edge_count);
  void link_edges();
  void bound_segments();
  void build_corners();

  const TriMesh& mesh_;
  double delta_;
  double min_segment_ = 0, max_segment_ = 0;
  // The edge Steiner node `node` lies on.
  std::uint32_t edge_of(std::uint32_t node) const { return node_edge_[node - nv_]; }
  // note: positions and edges apart, each array dense (24 and 4 bytes a node, where one record
  // took 32): a settled node's edge is read two nodes ahead (GeodesicQuery::prefetch_ahead).
  // note: edges (and so their Steiner points) in the Z order of their midpoints seen from above.
  HugeVector<std::array<double, 3>> nodes_;  // vertices first, then each edge's Steiner points
  HugeVector<std::uint32_t> node_edge_;      // per Steiner node (node - nv_): its edge
  std::uint32_t nv_ = 0;                     // the mesh's vertices
  std::vector<std::array<std::uint32_t, 3>> face_edges_;  // edge of (v0,v1), (v1,v2), (v2,v0)
  std::vector<std::uint32_t> edge_first_;  // while building: each edge's first node, + end
  // note: Dijkstra's time goes into cache misses, one per dependent load; so what a settled node
  // needs is gathered in one record: an edge's (one cache line) for a Steiner point, its
  // corners' (contiguous) for a vertex.
  struct alignas(64) Edge {
    std::uint32_t first = 0, end = 0;  // its Steiner nodes, running from ends[0] to ends[1]
    std::array<std::uint32_t, 2> ends{};
    struct Side {  // one face of the edge
      std::uint32_t face = kNoFace;
      std::uint32_t opposite = 0;                   // the face's corner off the edge
      std::array<std::uint32_t, 2> first{}, end{};  // Steiner nodes of its two other edges
    };
    std::array<Side, 2> sides;
  };
  struct Corner {  // a vertex in one of its faces
    std::uint32_t face = 0;
    std::array<std::uint32_t, 2> along{};            // nearest node on each of its two edges there
    std::uint32_t across_first = 0, across_end = 0;  // Steiner nodes of the opposite edge
  };
  HugeVector<Edge> edges_;
  std::vector<std::uint32_t> corner_first_;  // CSR vertex -> corners_
  HugeVector<Corner> corners_;
  std::vector<double> vertex_angle_;  // per vertex: vertex_angle() (empty: not kept)
};

// Dijkstra's tentative distances with an indexed 4-ary min-heap over them (decrease-key: each
// node is in the heap at most once). A node's distance and heap slot share one 16-byte label,
// so a relaxation touches one cache line of it.
class LabelHeap {
 public:
  struct Entry {
    double key;
    std::uint32_t node;
    std::uint32_t tag;  // caller's data, kept with the key (fills the entry's padding)
  };
  // All nodes at infinity, the heap empty.
  void reset(std::size_t nodes);
  // The label a distance gets (kept as is).
  static double key(double d) { return d; }
  double dist(std::uint32_t node) const { return label_[node].dist; }
  // The node's distance if it was popped, else infinity.
  double settled_dist(std::uint32_t node) const {
    const Label& l = label_[node];
    return l.slot == 0 ? l.dist : std::numeric_limits<double>::infinity();
  }
  // Lowers node's distance to key (which must be smaller), inserting it if not in the heap;
  // pred: the node it was reached from (kNone: the source point).
  void decrease(std::uint32_t node, double key, std::uint32_t tag, std::uint32_t pred);
  // The node a node's distance came from (kNone: the source point); valid once it is reached.
  std::uint32_t pred(std::uint32_t node) const { return label_[node].pred; }
  // The entry of least key into out (its node keeps its distance); false when none is left.
  bool pop(Entry& out);
  // The node most likely popped after `ahead` others (kNone: none known).
  std::uint32_t next_hint(std::size_t ahead) const {
    return ahead == 0 && !heap_.empty() ? heap_.front().node : kNone;
  }
  void prefetch_label(std::uint32_t) const {}
  // A popped node may be lowered again (a target: see BucketQueue::reopen); here none can be.
  void reopen(std::uint32_t) {}
  // Ends the search: pop answers false from now on (every popped distance is final).
  void finish() { finished_ = true; }
  static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

 private:
  struct Label {
    double dist;
    std::uint32_t slot;  // heap index + 1, 0: not in the heap
    std::uint32_t pred;  // the node its distance came from
  };
  void sift_up(std::size_t i, Entry e);
  std::vector<Entry> heap_;
  HugeVector<Label> label_;
  bool finished_ = false;
};

// Dijkstra's tentative distances in buckets of width at most the shortest graph edge (Dial's
// queue, for real weights): a node taken from the lowest bucket can be lowered by no node of
// that bucket, so a bucket's nodes may be settled in any order and each push and pop is O(1).
// Each lowering queues an entry (key, node, tag); the node's older entries are skipped when
// popped (their key is no longer its distance). The buckets live in a ring that spans the
// longest edge, which bounds the spread of the queued distances.
// Dist: how a node's distance is kept, double, or float for the anchored search (8 bytes a node
// less; its distances stand for paths that are pulled taut after, so only the order of near
// ties within a float's rounding, 6e-8 of the distance, can move).
template <typename Dist>
class BasicBucketQueue {
 public:
  using Entry = LabelHeap::Entry;
  // The number of buckets a graph needs, 0 if they are not worth it (degenerate faces, or a
  // longest edge too many times the shortest).
  static std::size_t ring_size(const SteinerGraph& graph);
  explicit BasicBucketQueue(const SteinerGraph& graph);
  void reset(std::size_t nodes);
  // The label a distance gets: rounded as kept. Relaxations compare their candidates rounded,
  // so that each lowering of a node is strictly lower.
  static double key(double d) { return static_cast<Dist>(d); }
  // The node's tentative distance; below zero once settled, so no relaxation improves it.
  double dist(std::uint32_t node) const { return dist_[node]; }
  double settled_dist(std::uint32_t node) const {
    const double l = dist_[node];
    return std::signbit(l) ? -l : std::numeric_limits<double>::infinity();
  }
  // key: as key() gives it.
  void decrease(std::uint32_t node, double key, std::uint32_t tag, std::uint32_t pred) {
    // note: b >= bucket_ (a distance never falls below the bucket being emptied: its nodes are
    // at least one width from the others) but for rounding, which the max guards against; and
    // b < bucket_ + ring size (no edge is longer than max_segment()). The width's margin covers
    // the rounding of multiplying by its inverse.
    const std::uint64_t b = bucket_of(key);
    dist_[node] = static_cast<Dist>(key);
    pred_[node] = pred;
    ring_[b & mask_].push_back({key, node, tag});
    ++queued_;
  }
  // A node of the lowest bucket with its distance and tag into out, marked settled; false when
  // none is left.
  bool pop(Entry& out);
  // note: past the current bucket, from the next ones (those of a search on a fine graph hold
  // a few entries each): their entries may still be lowered or skipped, a hint all the same.
  std::uint32_t next_hint(std::size_t ahead) const {
    std::size_t i = next_ + ahead;
    const std::uint64_t last = bucket_ + std::min<std::uint64_t>(kHintBuckets, mask_);
    for (std::uint64_t b = bucket_; b <= last; ++b) {
      const auto& q = ring_[b & mask_];
      if (i < q.size()) return q[i].node;
      i -= q.size();
    }
    return LabelHeap::kNone;
  }
  void prefetch_label(std::uint32_t node) const {
    __builtin_prefetch(&dist_[node]);
    __builtin_prefetch(&pred_[node], 1);
  }
  std::uint32_t pred(std::uint32_t node) const { return pred_[node]; }
  // Lets a popped node be lowered again: a target, whose last segment may be shorter than the
  // width, by a later node of the same bucket.
  void reopen(std::uint32_t node) { dist_[node] = std::fabs(dist_[node]); }
  // Ends the search once the current bucket is emptied: a distance popped from it is final
  // only then (a target's last segment may be shorter than the width).
  void finish() { finished_ = true; }

 private:
  // note: a settled node's distance is negated. The tag rides in the queued entries, so a
  // node holds 12 bytes (its distance and the node it came from), not 16; 8 with floats.
  // The bucket a distance goes into: never one already emptied.
  std::uint64_t bucket_of(double key) const {
    return std::max(static_cast<std::uint64_t>(key * per_width_), bucket_);
  }
  static constexpr std::uint64_t kHintBuckets = 3;  // buckets next_hint looks into past this
  double per_width_;  // 1 / bucket width
  std::vector<std::vector<Entry>> ring_;
  std::uint64_t mask_;  // ring size - 1
  HugeVector<Dist> dist_;
  HugeVector<std::uint32_t> pred_;
  std::uint64_t bucket_ = 0;  // the bucket being emptied
  std::size_t next_ = 0;      // its next entry
  std::size_t queued_ = 0;    // entries in the ring, skipped ones included
  bool finished_ = false;
};
using BucketQueue = BasicBucketQueue<double>;
using FloatBucketQueue = BasicBucketQueue<float>;

// Dijkstra on a SteinerGraph from one surface point to many. Holds per-query scratch memory:
// one per thread; the graph is shared read-only.
class GeodesicQuery {
 public:
  // Uses Dial's buckets where the graph allows (BucketQueue::ring_size), else a heap;
  // use_buckets = false forces the heap.
  explicit GeodesicQuery(const SteinerGraph& graph, bool use_buckets = true);

  // The memory (bytes) of one query on a graph of `nodes` nodes over `faces` faces with
  // `targets` targets: its labels (12 bytes per node and target; 8 anchored on buckets, counted
  // as 12 since a heap may take their place), a bit per face and the targets' lists by face,
  // and the queue's buckets.
  // An anchored query (set_anchored) needs sizeof(Anchor) more per Steiner node (counted here
  // per node).
  static std::size_t estimate_bytes(std::size_t nodes, std::size_t faces, std::size_t targets,
                                    bool anchored = false);

  // Distances from source to each target: min over boundary nodes u of the source's face and
  // v of the target's face of |source u| + path(u, v) + |v target| (and the straight segment
  // when both lie in one face). Stops as soon as the first `required` targets (all by default)
  // are settled; a later target not settled by then stays at infinity.
  void distances(const SurfacePoint& source, const std::vector<SurfacePoint>& targets,
                 std::vector<double>& out, std::size_t required = kAllTargets);
  static constexpr std::size_t kAllTargets = ~std::size_t{0};

  // A search bounded by a radius: settles every node within `radius` of source (at least;
  // fewer when all targets are settled first). Into out: each settled target's distance, else
  // infinity; into shell: the settled graph nodes farther than shell_from, with distances.
  // The settled distances stay readable (settled_distance) until the next query.
  void explore(const SurfacePoint& source, const std::vector<SurfacePoint>& targets, double radius,
               double shell_from, std::vector<std::pair<std::uint32_t, double>>& shell,
               std::vector<double>& out);
  // A graph node's distance from the last query's source if that query settled it, else
  // infinity.
  double settled_distance(std::uint32_t node) const {
    return last_ == kBuckets        ? buckets_->settled_dist(node)
           : last_ == kFloatBuckets ? float_buckets_->settled_dist(node)
                                    : heap_.settled_dist(node);
  }

  // The graph nodes of the shortest Steiner path the last query found from its source to its
  // target j (settled), in order from the source, into nodes: the source reaches the first
  // through its own face, each node the next through a face both lie on (or along an edge),
  // and the last the target through the target's face. Empty when the straight segment of one
  // face was shortest.
  void path(std::size_t target, std::vector<std::uint32_t>& nodes) const;
  // The node a graph node's distance came from in the last query (LabelHeap::kNone: the source).
  std::uint32_t pred(std::uint32_t node) const {
    return last_ == kBuckets        ? buckets_->pred(node)
           : last_ == kFloatBuckets ? float_buckets_->pred(node)
                                    : heap_.pred(node);
  }
  // The same for a graph node the last query settled: the path's nodes, `node` last.
  void path_to_node(std::uint32_t node, std::vector<std::uint32_t>& nodes) const;

  // Searches with straight segments across faces (see run_anchored in steiner_graph.cpp):
  // distances much nearer the exact geodesics than the graph's own, at a coarser delta.
  void set_anchored(bool anchored) { anchored_ = anchored; }
  bool anchored() const { return anchored_; }
  // With an anchored search: each label also keeps the node its path last bent at (4 bytes a
  // node more), so that a settled node's path can be told by its bends alone (bend()), after
  // the search's other labels are gone.
  // With waypoint_every > 0, a path is also told to pass the node it reached last before each
  // multiple of that distance (a waypoint, kept as a bend): so that between two, its route seen
  // from above strays little from the straight line.
  void set_track_bends(bool track, double waypoint_every = 0) {
    track_bends_ = track;
    per_waypoint_ = waypoint_every > 0 ? 1 / waypoint_every : 0;
  }
  // The node the path of a node the last (anchored, tracking) query reached last bent at
  // before it (LabelHeap::kNone: none, straight from the source); the path runs straight (in
  // the unfolding of the faces it crosses) from there to the node.
  std::uint32_t bend(std::uint32_t node) const {
    const std::size_t nv = g_.mesh().vertex_count();
    return node < nv ? vertex_bends_[node] : anchors_[node - nv].bend;
  }

  // Graph nodes the last query settled (the area it searched).
  std::size_t settled() const { return settled_; }

  // Whether the queries use Dial's buckets (else the heap); same distances up to rounding.
  bool uses_buckets() const { return use_buckets_; }

 private:
  // explore(), or distances() with an infinite radius and no shell, on the graph's queue.
  void search(const SurfacePoint& source, const std::vector<SurfacePoint>& targets, double radius,
              double shell_from, std::vector<std::pair<std::uint32_t, double>>* shell,
              std::vector<double>& out, std::size_t required);
  // The targets listed by face (face_heads_, target_next_, target_faces_), none done.
  void index_targets(const std::vector<SurfacePoint>& targets);
  // The last target in face f, -1: none (then target_next_ from it).
  std::int32_t first_target(std::uint32_t f) const;
  // Dijkstra's loop: pops until the queue is empty or finished; a popped target is settled
  // (settle_target), any other node counted, checked against the radius and the shell, then
  // relaxed by relax(node, distance, tag).
  template <typename Queue, typename Relax>
  void settle(Queue& queue, double radius, double shell_from,
              std::vector<std::pair<std::uint32_t, double>>* shell, std::size_t required,
              Relax&& relax);
  // Target j popped: done, the search finished once the first `required` are.
  template <typename Queue>
  void settle_target(Queue& queue, std::size_t j, std::size_t required, std::size_t& remaining);
  // Prefetches the records of the nodes the queue will most likely settle next.
  template <typename Queue>
  void prefetch_ahead(const Queue& queue) const;
  // The done targets' distances into out.
  template <typename Queue>
  void collect_targets(const Queue& queue, const std::vector<SurfacePoint>& targets,
                       std::vector<double>& out);
  // The anchored search's relaxations (steiner_graph.cpp).
  template <typename Queue>
  class Anchored;
  template <typename Queue>
  void run_anchored(Queue& queue, const SurfacePoint& source,
                    const std::vector<SurfacePoint>& targets, double radius, double shell_from,
                    std::vector<std::pair<std::uint32_t, double>>* shell, std::vector<double>& out,
                    std::size_t required);
  template <typename Queue>
  void run(Queue& queue, const SurfacePoint& source, const std::vector<SurfacePoint>& targets,
           double radius, double shell_from, std::vector<std::pair<std::uint32_t, double>>* shell,
           std::vector<double>& out, std::size_t required);
  const SteinerGraph& g_;
  LabelHeap heap_;
  // The plain search's buckets, and the anchored search's (floats): each made when first used,
  // where the graph allows buckets.
  bool use_buckets_ = false;
  std::unique_ptr<BucketQueue> buckets_;
  std::unique_ptr<FloatBucketQueue> float_buckets_;
  enum { kHeap, kBuckets, kFloatBuckets } last_ = kHeap;  // the queue of the last search
  // (face, its list's head) for each face with a target, by face: a few entries, where an
  // array over the faces would take 4 bytes a face per search.
  std::vector<std::pair<std::uint32_t, std::int32_t>> face_heads_;
  std::vector<std::uint64_t> target_faces_;  // bit per face: has a target (fits in cache)
  std::vector<std::int32_t> target_next_;
  std::vector<char> target_done_;  // target settled (its distance final once the search ends)
  std::vector<std::uint32_t> nodes_;
  std::size_t settled_ = 0;
  bool anchored_ = false;
  bool track_bends_ = false;
  double per_waypoint_ = 0;
  // An anchored label: the point its straight segment starts from (offset from the node, in
  // the plane of the face it came through), and the part of the node's edge the point sees
  // through the faces crossed, as fractions of the edge from its first end in 1/65535ths
  // (rounded outwards); with track_bends_, its bend. Steiner nodes only: a path through a
  // vertex bends there. note: the point's own distance is not kept: it is the node's less the
  // offset's length (20 bytes a node, not 32).
  struct Anchor {
    float off[3];
    std::uint16_t lo, hi;
    std::uint32_t bend;
  };
  HugeVector<Anchor> anchors_;
  HugeVector<std::uint32_t> vertex_bends_;  // with track_bends_, the vertices' bends
};

}  // namespace dpts::core

// Geodesic distances on a TIN approximated on the Steiner graph of "Distance Preserving Terrain
// Simplification" (the paper in ../shared/paper), section 2.1: floor(len(e)/delta) points inside
// every edge e, and inside every triangle a straight segment between every pair of points on its
// boundary (corners included). The graph is implicit: a triangle's clique is generated when
// Dijkstra reaches it, so memory is linear in the number of Steiner points.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dpts::core {

// A triangle mesh in metres: x, y in a metric CRS, z height. Faces counter-clockwise.
struct TriMesh {
  std::vector<double> xyz;
  std::vector<std::array<std::uint32_t, 3>> faces;
  std::size_t vertex_count() const { return xyz.size() / 3; }
};

// Mean 3D length of the mesh's edges (each undirected edge once).
double mean_edge_length(const TriMesh& mesh);

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
  // an edge has more than two faces, delta is not positive, or the graph would have more than
  // kMaxNodes nodes (checked before allocating). The mesh must outlive the graph.
  SteinerGraph(const TriMesh& mesh, double delta);

  const TriMesh& mesh() const { return mesh_; }
  double delta() const { return delta_; }
  std::size_t node_count() const { return pos_.size() / 3; }
  std::size_t steiner_count() const { return node_count() - mesh_.vertex_count(); }
  const double* position(std::uint32_t node) const { return &pos_[3 * node]; }

  // The nodes on face f's boundary (its corners and its edges' Steiner points), into out.
  void face_nodes(std::uint32_t f, std::vector<std::uint32_t>& out) const;

  // Calls node_fn(v) for every node v joined to `node` by a graph edge, except that along the
  // node's own edges only the nearest node on each side is given: the others lie on the same
  // straight line, so the path through the nearest one has the same length (and Dijkstra finds
  // it). Calls face_fn(f) for every face the node lies on.
  template <typename NodeFn, typename FaceFn>
  void for_each_neighbour(std::uint32_t node, NodeFn&& node_fn, FaceFn&& face_fn) const {
    const std::uint32_t nv = static_cast<std::uint32_t>(mesh_.vertex_count());
    auto edge_interior = [&](std::uint32_t e) {
      for (std::uint32_t n = edge_first_[e]; n < edge_first_[e + 1]; ++n) node_fn(n);
    };
    if (node < nv) {
      for (std::uint32_t k = vertex_face_first_[node]; k < vertex_face_first_[node + 1]; ++k) {
        const std::uint32_t f = vertex_faces_[k];
        const auto& fv = mesh_.faces[f];
        const int i = fv[0] == node ? 0 : fv[1] == node ? 1 : 2;
        // Along the two edges at this corner: the first node on each.
        for (int li : {i, (i + 2) % 3}) {
          const std::uint32_t e = face_edges_[f][li];
          if (edge_first_[e] == edge_first_[e + 1]) {
            node_fn(edge_ends_[e][0] == node ? edge_ends_[e][1] : edge_ends_[e][0]);
          } else {
            node_fn(edge_ends_[e][0] == node ? edge_first_[e] : edge_first_[e + 1] - 1);
          }
        }
        edge_interior(face_edges_[f][(i + 1) % 3]);  // across the face
        face_fn(f);
      }
      return;
    }
    const std::uint32_t e = node_edge_[node - nv];
    node_fn(node == edge_first_[e] ? edge_ends_[e][0] : node - 1);
    node_fn(node + 1 == edge_first_[e + 1] ? edge_ends_[e][1] : node + 1);
    for (std::uint32_t f : edge_faces_[e]) {
      if (f == kNoFace) continue;
      const int li = face_edges_[f][0] == e ? 0 : face_edges_[f][1] == e ? 1 : 2;
      node_fn(mesh_.faces[f][(li + 2) % 3]);  // the opposite corner
      edge_interior(face_edges_[f][(li + 1) % 3]);
      edge_interior(face_edges_[f][(li + 2) % 3]);
      face_fn(f);
    }
  }
  static constexpr std::uint32_t kNoFace = 0xFFFFFFFFu;

 private:
  const TriMesh& mesh_;
  double delta_;
  std::vector<double> pos_;                               // node positions, vertices first
  std::vector<std::array<std::uint32_t, 3>> face_edges_;  // edge of (v0,v1), (v1,v2), (v2,v0)
  std::vector<std::array<std::uint32_t, 2>> edge_faces_;
  std::vector<std::uint32_t> edge_first_;  // first Steiner node of each edge, + end
  std::vector<std::array<std::uint32_t, 2>>
      edge_ends_;                         // (lower, higher) vertex; nodes run low -> high
  std::vector<std::uint32_t> node_edge_;  // Steiner node - vertex_count -> edge
  std::vector<std::uint32_t> vertex_face_first_, vertex_faces_;  // CSR vertex -> faces
};

// An indexed 4-ary min-heap of node ids keyed by distance, with decrease-key: each node is in
// the heap at most once (fewer entries than a lazy heap with duplicates).
class NodeHeap {
 public:
  void reset(std::size_t nodes);
  bool empty() const { return heap_.empty(); }
  // Inserts node or lowers its key (key must not be larger than the current one).
  void push_or_decrease(std::uint32_t node, double key);
  std::pair<double, std::uint32_t> pop();

 private:
  struct Entry {
    double key;
    std::uint32_t node;
  };
  void sift_up(std::size_t i, Entry e);
  std::vector<Entry> heap_;
  std::vector<std::uint32_t> pos_;  // node -> heap index + 1, 0: not in the heap
};

// Dijkstra on a SteinerGraph from one surface point to many. Holds per-query scratch memory:
// one per thread; the graph is shared read-only.
class GeodesicQuery {
 public:
  explicit GeodesicQuery(const SteinerGraph& graph);

  // Distances from source to each target: min over boundary nodes u of the source's face and
  // v of the target's face of |source u| + path(u, v) + |v target| (and the straight segment
  // when both lie in one face). Stops as soon as every target is settled.
  void distances(const SurfacePoint& source, const std::vector<SurfacePoint>& targets,
                 std::vector<double>& out);

 private:
  const SteinerGraph& g_;
  std::vector<double> dist_;
  NodeHeap heap_;
  std::vector<std::int32_t> face_target_head_;  // first target in a face, -1: none
  std::vector<std::int32_t> target_next_;
  std::vector<std::uint32_t> nodes_;
};

}  // namespace dpts::core

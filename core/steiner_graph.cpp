// The Steiner graph of a TIN and Dijkstra queries on it (the DPTS paper, section 2.1).
#include "core/steiner_graph.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

namespace dpts::core {
namespace {

double dist3(const double* a, const double* b) {
  const double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// (min, max) vertex key of every face edge, with its face and local index, sorted.
// note: by a counting sort on the lower vertex (the faces in order, so each bucket's entries
// come in face order), then each bucket (a vertex's few edges) sorted: the same order as one
// sort of the tuples, in linear time (San Gabriel's T, 4.6M face edges: one sort took 0.45 s,
// done three times, serial, before the geodesics could start).
std::vector<std::tuple<std::uint64_t, std::uint32_t, int>> sorted_face_edges(const TriMesh& m) {
  using Entry = std::tuple<std::uint64_t, std::uint32_t, int>;
  const std::size_t nv = m.vertex_count(), n = 3 * m.faces.size();
  auto key = [&](std::size_t f, int i) {
    const std::uint32_t a = m.faces[f][i], b = m.faces[f][(i + 1) % 3];
    return (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
  };
  // note: every caller then reads the corners' positions: an index past them is refused here.
  for (const auto& t : m.faces) {
    if (t[0] >= nv || t[1] >= nv || t[2] >= nv) {
      throw std::invalid_argument("a face's vertex index is out of range");
    }
  }
  std::vector<std::size_t> end(nv + 1, 0);
  for (std::size_t f = 0; f < m.faces.size(); ++f) {
    for (int i = 0; i < 3; ++i) ++end[(key(f, i) >> 32) + 1];
  }
  for (std::size_t v = 0; v < nv; ++v) end[v + 1] += end[v];
  std::vector<Entry> e(n);
  for (std::uint32_t f = 0; f < m.faces.size(); ++f) {
    for (int i = 0; i < 3; ++i) {
      const std::uint64_t k = key(f, i);
      e[end[k >> 32]++] = Entry{k, f, i};
    }
  }
  for (std::size_t v = 0, first = 0; v < nv; first = end[v++]) {
    std::sort(e.begin() + static_cast<std::ptrdiff_t>(first),
              e.begin() + static_cast<std::ptrdiff_t>(end[v]));
  }
  return e;
}

// The graph's node count (vertices and floor(len / delta) per edge; a double, so that a count
// past 32 bits is seen) and edge count, from the sorted face edges.
std::pair<double, std::size_t> count_nodes(
    const TriMesh& m, const std::vector<std::tuple<std::uint64_t, std::uint32_t, int>>& e,
    double delta) {
  double nodes = static_cast<double>(m.vertex_count());
  std::size_t edges = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (i > 0 && std::get<0>(e[i]) == std::get<0>(e[i - 1])) continue;
    ++edges;
    const std::uint64_t key = std::get<0>(e[i]);
    nodes += std::floor(dist3(&m.xyz[3 * (key >> 32)], &m.xyz[3 * (key & 0xFFFFFFFFu)]) / delta);
  }
  return {nodes, edges};
}

// Bits 0-15 of v spread to the even bits 0-30.
std::uint64_t spread16(std::uint64_t v) {
  v &= 0xFFFFu;
  v = (v | (v << 8)) & 0x00FF00FFu;
  v = (v | (v << 4)) & 0x0F0F0F0Fu;
  v = (v | (v << 2)) & 0x33333333u;
  v = (v | (v << 1)) & 0x55555555u;
  return v;
}

// The box of the mesh's vertices seen from above (lo, hi) and the scale that maps it onto
// [0, 65535]^2 (0 along an axis it has no extent in).
struct ZFrame {
  double lo[2], scale[2];
  explicit ZFrame(const TriMesh& m) {
    double hi[2];
    for (int c = 0; c < 2; ++c) {
      lo[c] = std::numeric_limits<double>::infinity();
      hi[c] = -lo[c];
    }
    for (std::size_t v = 0; v < m.vertex_count(); ++v) {
      for (int c = 0; c < 2; ++c) {
        lo[c] = std::min(lo[c], m.xyz[3 * v + c]);
        hi[c] = std::max(hi[c], m.xyz[3 * v + c]);
      }
    }
    for (int c = 0; c < 2; ++c) scale[c] = hi[c] > lo[c] ? 65535.0 / (hi[c] - lo[c]) : 0.0;
  }
  // The Z order key of the point (x, y).
  std::uint64_t key(double x, double y) const {
    const double p[2] = {x, y};
    std::uint64_t q[2];
    for (int c = 0; c < 2; ++c) {
      const double t = (p[c] - lo[c]) * scale[c];
      q[c] = t > 0 ? static_cast<std::uint64_t>(std::min(t, 65535.0)) : 0;
    }
    return spread16(q[0]) | spread16(q[1]) << 1;
  }
};

// The edges (each the first of its run in the sorted face edges e) in the Z order of their
// midpoints seen from above, ties by their vertices: (order key, first face edge).
std::vector<std::pair<std::uint64_t, std::size_t>> z_order(
    const TriMesh& m, const std::vector<std::tuple<std::uint64_t, std::uint32_t, int>>& e,
    std::size_t edge_count) {
  const ZFrame z(m);
  std::vector<std::pair<std::uint64_t, std::size_t>> order;
  order.reserve(edge_count);
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (i > 0 && std::get<0>(e[i]) == std::get<0>(e[i - 1])) continue;
    const std::uint64_t key = std::get<0>(e[i]);
    const double* a = &m.xyz[3 * (key >> 32)];
    const double* b = &m.xyz[3 * (key & 0xFFFFFFFFu)];
    order.emplace_back(z.key((a[0] + b[0]) / 2, (a[1] + b[1]) / 2), i);
  }
  std::sort(order.begin(), order.end());
  return order;
}
}  // namespace

void order_vertices_spatially(TriMesh& mesh) {
  const std::size_t n = mesh.vertex_count();
  std::vector<std::uint32_t> old_of;
  {
    const ZFrame z(mesh);
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order(n);
    for (std::size_t v = 0; v < n; ++v) {
      order[v] = {z.key(mesh.xyz[3 * v], mesh.xyz[3 * v + 1]), static_cast<std::uint32_t>(v)};
    }
    std::sort(order.begin(), order.end());
    old_of.resize(n);
    for (std::size_t i = 0; i < n; ++i) old_of[i] = order[i].second;
  }
  std::vector<double> xyz(3 * n);
  std::vector<std::uint32_t> new_of(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::copy_n(mesh.xyz.begin() + 3 * old_of[i], 3, xyz.begin() + 3 * i);
    new_of[old_of[i]] = static_cast<std::uint32_t>(i);
  }
  mesh.xyz = std::move(xyz);
  for (auto& f : mesh.faces) {
    for (auto& v : f) v = new_of[v];
  }
}

double mean_edge_length(const TriMesh& mesh) {
  const auto e = sorted_face_edges(mesh);
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (i > 0 && std::get<0>(e[i]) == std::get<0>(e[i - 1])) continue;
    const auto key = std::get<0>(e[i]);
    sum += dist3(&mesh.xyz[3 * (key >> 32)], &mesh.xyz[3 * (key & 0xFFFFFFFFu)]);
    ++n;
  }
  return n ? sum / n : 0.0;
}

SteinerGraph::SteinerGraph(const TriMesh& mesh, double delta) : mesh_(mesh), delta_(delta) {
  nv_ = static_cast<std::uint32_t>(mesh.vertex_count());
  if (!(delta > 0)) throw std::invalid_argument("Steiner spacing delta must be positive");
  face_edges_.resize(mesh.faces.size());
  const auto e = sorted_face_edges(mesh);
  // Count the nodes before allocating any: a mesh far larger than delta (or with a non-finite
  // coordinate) is refused here, not by running out of memory.
  const auto [nodes, edge_count] = count_nodes(mesh, e, delta);
  if (!(nodes < static_cast<double>(kMaxNodes))) {
    throw std::invalid_argument("too many Steiner points (" + std::to_string(nodes) + "; at most " +
                                std::to_string(kMaxNodes) + ")");
  }
  build_nodes(e, static_cast<std::size_t>(nodes), edge_count);
  link_edges();
  bound_segments();
  build_corners();
  // note: the edge records hold each edge's nodes from here on.
  edge_first_ = std::vector<std::uint32_t>();
}

// The vertices' nodes, then each edge (from the sorted face edges, two faces at most) with its
// Steiner points: floor(len / delta) evenly inside it.
void SteinerGraph::build_nodes(const std::vector<std::tuple<std::uint64_t, std::uint32_t, int>>& e,
                               std::size_t nodes, std::size_t edge_count) {
  const TriMesh& mesh = mesh_;
  const double delta = delta_;
  const std::size_t nv = mesh.vertex_count();
  nodes_.reserve(nodes);
  node_edge_.reserve(nodes - nv);
  for (std::size_t v = 0; v < nv; ++v) {
    nodes_.push_back({mesh.xyz[3 * v], mesh.xyz[3 * v + 1], mesh.xyz[3 * v + 2]});
  }
  edges_.reserve(edge_count);
  edge_first_.reserve(edge_count + 1);
  edge_first_.push_back(static_cast<std::uint32_t>(nv));
  // note: edges in Z order, not by their vertex ids: a search's frontier then reads records
  // that lie near each other in memory (San Gabriel's T searched 15 % faster).
  for (const auto& zi : z_order(mesh, e, edge_count)) {
    std::size_t i = zi.second;
    const std::uint64_t key = std::get<0>(e[i]);
    const std::uint32_t edge = static_cast<std::uint32_t>(edges_.size());
    std::array<std::uint32_t, 2> faces{kNoFace, kNoFace};
    int n = 0;
    for (; i < e.size() && std::get<0>(e[i]) == key; ++i, ++n) {
      if (n >= 2) throw std::invalid_argument("mesh has an edge shared by more than two faces");
      faces[n] = std::get<1>(e[i]);
      face_edges_[std::get<1>(e[i])][std::get<2>(e[i])] = edge;
    }
    Edge rec;
    rec.ends = {static_cast<std::uint32_t>(key >> 32),
                static_cast<std::uint32_t>(key & 0xFFFFFFFFu)};
    for (int side = 0; side < 2; ++side) rec.sides[side].face = faces[side];
    edges_.push_back(rec);
    const double* a = &mesh.xyz[3 * (key >> 32)];
    const double* b = &mesh.xyz[3 * (key & 0xFFFFFFFFu)];
    const auto k = static_cast<std::uint32_t>(std::floor(dist3(a, b) / delta));
    for (std::uint32_t j = 1; j <= k; ++j) {
      const double t = static_cast<double>(j) / (k + 1);
      nodes_.push_back(
          {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])});
      node_edge_.push_back(edge);
    }
    edge_first_.push_back(static_cast<std::uint32_t>(nodes_.size()));
  }
}

// Each edge's record: its nodes, and per face the opposite corner and the other two edges.
void SteinerGraph::link_edges() {
  const TriMesh& mesh = mesh_;
  for (std::uint32_t i = 0; i < edges_.size(); ++i) {
    Edge& rec = edges_[i];
    rec.first = edge_first_[i];
    rec.end = edge_first_[i + 1];
    for (auto& side : rec.sides) {
      if (side.face == kNoFace) continue;
      const auto& fe = face_edges_[side.face];
      const int li = fe[0] == i ? 0 : fe[1] == i ? 1 : 2;
      side.opposite = mesh.faces[side.face][(li + 2) % 3];
      for (int k = 0; k < 2; ++k) {
        const std::uint32_t other = fe[(li + 1 + k) % 3];
        side.first[k] = edge_first_[other];
        side.end[k] = edge_first_[other + 1];
      }
    }
  }
}

// Segment length bounds. Two distinct nodes of a face lie on one edge (at least its node
// spacing apart) or on two edges meeting at a corner with angle t: then one of them is at least
// its edge's spacing s from the corner, and so at least s min(1, sin t) from the other edge.
// The longest segment is the face's longest edge.
void SteinerGraph::bound_segments() {
  const TriMesh& mesh = mesh_;
  auto spacing = [&](std::uint32_t e, double len) {
    return len / static_cast<double>(edge_first_[e + 1] - edge_first_[e] + 1);
  };
  min_segment_ = std::numeric_limits<double>::infinity();
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const double* p[3];
    for (int i = 0; i < 3; ++i) p[i] = &mesh.xyz[3 * mesh.faces[f][i]];
    double len[3], s[3];
    for (int i = 0; i < 3; ++i) {
      len[i] = dist3(p[i], p[(i + 1) % 3]);  // edge i runs from corner i to corner i + 1
      s[i] = spacing(face_edges_[f][i], len[i]);
      max_segment_ = std::max(max_segment_, len[i]);
    }
    for (int i = 0; i < 3; ++i) {
      // Corner i joins edge i and edge i + 2.
      const int j = (i + 2) % 3;
      double a[3], b[3];
      for (int c = 0; c < 3; ++c) {
        a[c] = p[(i + 1) % 3][c] - p[i][c];
        b[c] = p[j][c] - p[i][c];
      }
      const double cx = a[1] * b[2] - a[2] * b[1], cy = a[2] * b[0] - a[0] * b[2],
                   cz = a[0] * b[1] - a[1] * b[0];
      const double sin_t = std::sqrt(cx * cx + cy * cy + cz * cz) / (len[i] * len[j]);
      const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
      const double factor = dot <= 0 ? 1.0 : std::min(1.0, sin_t);
      min_segment_ = std::min(min_segment_, std::min(s[i], s[j]) * factor);
    }
  }
  if (!(min_segment_ > 0) || mesh.faces.empty()) min_segment_ = 0;
}

// Vertex -> its corners (CSR), each with the first node along its two edges and the Steiner
// nodes across.
void SteinerGraph::build_corners() {
  const TriMesh& mesh = mesh_;
  const std::size_t nv = mesh.vertex_count();
  corner_first_.assign(nv + 1, 0);
  for (const auto& f : mesh.faces) {
    for (auto v : f) ++corner_first_[v + 1];
  }
  for (std::size_t v = 0; v < nv; ++v) corner_first_[v + 1] += corner_first_[v];
  corners_.resize(corner_first_[nv]);
  std::vector<std::uint32_t> fill(corner_first_.begin(), corner_first_.end() - 1);
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t v = mesh.faces[f][i];
      Corner& c = corners_[fill[v]++];
      c.face = f;
      // Along the two edges at this corner: the first node on each (the far corner if none).
      for (int k = 0; k < 2; ++k) {
        const Edge& rec = edges_[face_edges_[f][k == 0 ? i : (i + 2) % 3]];
        const bool from_low = rec.ends[0] == v;
        if (rec.first == rec.end) {
          c.along[k] = from_low ? rec.ends[1] : rec.ends[0];
        } else {
          c.along[k] = from_low ? rec.first : rec.end - 1;
        }
      }
      const std::uint32_t across = face_edges_[f][(i + 1) % 3];
      c.across_first = edge_first_[across];
      c.across_end = edge_first_[across + 1];
    }
  }
}

double SteinerGraph::corner_angle(std::uint32_t f, std::uint32_t v) const {
  const auto& face = mesh_.faces[f];
  const int i = face[0] == v ? 0 : face[1] == v ? 1 : 2;
  const double* p = &mesh_.xyz[3 * v];
  const double* a = &mesh_.xyz[3 * face[(i + 1) % 3]];
  const double* b = &mesh_.xyz[3 * face[(i + 2) % 3]];
  const double u[3] = {a[0] - p[0], a[1] - p[1], a[2] - p[2]};
  const double w[3] = {b[0] - p[0], b[1] - p[1], b[2] - p[2]};
  const double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                       u[0] * w[1] - u[1] * w[0]};
  return std::atan2(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
                    u[0] * w[0] + u[1] * w[1] + u[2] * w[2]);
}

std::uint32_t SteinerGraph::across_edge(std::uint32_t f, std::uint32_t v, std::uint32_t x) const {
  const auto& face = mesh_.faces[f];
  for (int i = 0; i < 3; ++i) {
    const std::uint32_t a = face[i], b = face[(i + 1) % 3];
    if ((a == v && b == x) || (a == x && b == v)) return across(f, i);
  }
  return kNoFace;
}

SteinerGraph::Fan SteinerGraph::walk_fan(std::uint32_t v, std::uint32_t f, std::uint32_t x) const {
  Fan fan;
  fan.angle = corner_angle(f, v);
  fan.faces = 1;
  std::uint32_t cur = f;
  for (int step = 0; step < kMaxFan; ++step) {
    const std::uint32_t next = across_edge(cur, v, x);
    if (next == kNoFace) return fan;
    if (next == f) {
      fan.closed = true;
      return fan;
    }
    fan.angle += corner_angle(next, v);
    ++fan.faces;
    x = third_corner(next, v, x);
    cur = next;
  }
  return fan;
}

// Each vertex's total angle, walked round its fan from its first corner's face as
// PathStraightener walks it from a face of its path, so that the straightener reads it
// instead of walking for each bend (its atan2 calls were 3 % of dpts-eval's time on San
// Gabriel).
void SteinerGraph::keep_vertex_angles() {
  const std::size_t nv = mesh_.vertex_count();
  vertex_angle_.assign(nv, std::numeric_limits<double>::quiet_NaN());
  for (std::uint32_t v = 0; v < nv; ++v) {
    const std::uint32_t faces = corner_first_[v + 1] - corner_first_[v];
    if (faces == 0) continue;
    const std::uint32_t f = corners_[corner_first_[v]].face;
    const std::uint32_t x = third_corner(f, v, kNoFace);
    const Fan fan = walk_fan(v, f, x);
    // note: a fan that is not all of v's faces (fans meeting at v) is left to the caller's
    // walk: its answer depends on the face it starts from.
    if (fan.closed) {
      if (fan.faces == faces) vertex_angle_[v] = fan.angle;
      continue;
    }
    // On the outline: -1 where one open fan holds all of v's faces (walked both ways from f).
    const Fan back = walk_fan(v, f, third_corner(f, v, x));
    if (!back.closed && fan.faces + back.faces - 1 == faces &&
        faces <= static_cast<std::uint32_t>(kMaxFan)) {
      vertex_angle_[v] = -1;
    }
  }
}

SteinerGraph::Estimate SteinerGraph::estimate(const TriMesh& mesh, double delta) {
  const auto e = sorted_face_edges(mesh);
  const auto [nodes, edges] = count_nodes(mesh, e, delta);
  Estimate est;
  est.nodes = nodes < static_cast<double>(kMaxNodes) ? static_cast<std::size_t>(nodes) : kMaxNodes;
  // Per node its record; per edge its record and first node; per face its edges and 3 corners;
  // per vertex its first corner and its total angle (kept only for straightened paths, counted
  // always: a bound); plus the sorted face edges and their Z order, which construction holds
  // meanwhile.
  const std::size_t nf = mesh.faces.size();
  est.bytes = est.nodes * (sizeof(nodes_[0]) + sizeof(node_edge_[0])) + edges * (sizeof(Edge) + 4) +
              nf * (sizeof(std::array<std::uint32_t, 3>) + 3 * sizeof(Corner)) +
              (4 + sizeof(double)) * mesh.vertex_count() + e.size() * sizeof(e[0]) +
              edges * sizeof(std::pair<std::uint64_t, std::size_t>);
  return est;
}

void SteinerGraph::face_nodes(std::uint32_t f, std::vector<std::uint32_t>& out) const {
  out.clear();
  for (int i = 0; i < 3; ++i) out.push_back(mesh_.faces[f][i]);
  for (int i = 0; i < 3; ++i) {
    const std::uint32_t e = face_edges_[f][i];
    for (std::uint32_t n = edges_[e].first; n < edges_[e].end; ++n) out.push_back(n);
  }
}

void SteinerGraph::edge_nodes(std::uint32_t f, int i, std::vector<std::uint32_t>& out) const {
  out.clear();
  const std::uint32_t a = mesh_.faces[f][i], b = mesh_.faces[f][(i + 1) % 3];
  const std::uint32_t e = face_edges_[f][i];
  out.push_back(a);
  // note: an edge's Steiner nodes run from its lower vertex id to its higher.
  if (a < b) {
    for (std::uint32_t n = edges_[e].first; n < edges_[e].end; ++n) out.push_back(n);
  } else {
    for (std::uint32_t n = edges_[e].end; n-- > edges_[e].first;) out.push_back(n);
  }
  out.push_back(b);
}

void LabelHeap::reset(std::size_t nodes) {
  heap_.clear();
  finished_ = false;
  label_.assign(nodes, {std::numeric_limits<double>::infinity(), 0, kNone});
}

void LabelHeap::sift_up(std::size_t i, Entry e) {
  while (i > 0) {
    const std::size_t parent = (i - 1) / 4;
    if (!(e.key < heap_[parent].key)) break;
    heap_[i] = heap_[parent];
    label_[heap_[i].node].slot = static_cast<std::uint32_t>(i + 1);
    i = parent;
  }
  heap_[i] = e;
  label_[e.node].slot = static_cast<std::uint32_t>(i + 1);
}

void LabelHeap::decrease(std::uint32_t node, double key, std::uint32_t tag, std::uint32_t pred) {
  Label& l = label_[node];
  l.dist = key;
  l.pred = pred;
  if (l.slot == 0) {
    heap_.push_back({key, node, tag});
    sift_up(heap_.size() - 1, {key, node, tag});
  } else {
    sift_up(l.slot - 1, {key, node, tag});
  }
}

bool LabelHeap::pop(Entry& out) {
  if (heap_.empty() || finished_) return false;
  const Entry top = heap_.front();
  label_[top.node].slot = 0;
  const Entry last = heap_.back();
  heap_.pop_back();
  if (!heap_.empty()) {
    // Sift `last` down from the root.
    std::size_t i = 0;
    const std::size_t n = heap_.size();
    for (;;) {
      const std::size_t c0 = 4 * i + 1;
      if (c0 >= n) break;
      std::size_t best = c0;
      const std::size_t c_end = std::min(c0 + 4, n);
      for (std::size_t c = c0 + 1; c < c_end; ++c) {
        if (heap_[c].key < heap_[best].key) best = c;
      }
      if (!(heap_[best].key < last.key)) break;
      heap_[i] = heap_[best];
      label_[heap_[i].node].slot = static_cast<std::uint32_t>(i + 1);
      i = best;
    }
    heap_[i] = last;
    label_[last.node].slot = static_cast<std::uint32_t>(i + 1);
  }
  out = top;
  return true;
}

namespace {

// note: the bucket width keeps a relative margin below the shortest segment, so that rounding
// cannot put a node relaxed from bucket b back into bucket b.
double bucket_width(const SteinerGraph& graph) { return graph.min_segment() * (1 - 1e-6); }

}  // namespace

template <typename Dist>
std::size_t BasicBucketQueue<Dist>::ring_size(const SteinerGraph& graph) {
  const double width = bucket_width(graph);
  if (!(width > 0)) return 0;
  const double ring = std::floor(graph.max_segment() / width) + 2;
  constexpr double kMaxRing = 1 << 16;  // beyond this the empty buckets cost more than a heap
  if (!(ring <= kMaxRing)) return 0;
  // note: a power of two, so that a bucket's slot is a mask, not a division.
  std::size_t size = 1;
  while (static_cast<double>(size) < ring) size *= 2;
  return size;
}

template <typename Dist>
BasicBucketQueue<Dist>::BasicBucketQueue(const SteinerGraph& graph)
    : per_width_(1 / bucket_width(graph)), ring_(ring_size(graph)), mask_(ring_.size() - 1) {}

template <typename Dist>
void BasicBucketQueue<Dist>::reset(std::size_t nodes) {
  for (auto& b : ring_) b.clear();
  dist_.assign(nodes, std::numeric_limits<Dist>::infinity());
  pred_.assign(nodes, LabelHeap::kNone);
  bucket_ = 0;
  next_ = 0;
  queued_ = 0;
  finished_ = false;
}

template <typename Dist>
bool BasicBucketQueue<Dist>::pop(Entry& out) {
  while (queued_ > 0) {
    auto& bucket = ring_[bucket_ & mask_];
    if (next_ == bucket.size()) {
      if (finished_) return false;
      bucket.clear();
      next_ = 0;
      ++bucket_;
      continue;
    }
    const Entry e = bucket[next_++];
    --queued_;
    Dist& l = dist_[e.node];
    // note: settled (negative), or lowered since (an older entry). A key is never set twice
    // (each lowering is strictly lower), so one entry matches.
    if (l != e.key) continue;
    out = e;
    l = -l;
    return true;
  }
  return false;
}

template class BasicBucketQueue<double>;
template class BasicBucketQueue<float>;

GeodesicQuery::GeodesicQuery(const SteinerGraph& graph, bool use_buckets)
    : g_(graph), use_buckets_(use_buckets && BucketQueue::ring_size(graph) > 0) {}

std::size_t GeodesicQuery::estimate_bytes(std::size_t nodes, std::size_t faces, std::size_t targets,
                                          bool anchored) {
  // note: the buckets hold the queued entries (the search's frontier, far fewer than the
  // nodes); a quarter of an entry per node bounds them on the meshes measured. The heap, for
  // the graphs that cannot have buckets (not known before the graph is built), holds 16 bytes
  // a node, the buckets' 12 (8 for the anchored search's floats) and entries: 16 bounds both.
  return (nodes + targets) * 12 + nodes * 4 + faces / 8 + targets * 24 +
         (anchored ? nodes * sizeof(Anchor) : 0);
}

void GeodesicQuery::distances(const SurfacePoint& source, const std::vector<SurfacePoint>& targets,
                              std::vector<double>& out, std::size_t required) {
  out.assign(targets.size(), std::numeric_limits<double>::infinity());
  required = std::min(required, targets.size());
  if (required == 0) return;
  const double inf = std::numeric_limits<double>::infinity();
  search(source, targets, inf, inf, nullptr, out, required);
}

void GeodesicQuery::explore(const SurfacePoint& source, const std::vector<SurfacePoint>& targets,
                            double radius, double shell_from,
                            std::vector<std::pair<std::uint32_t, double>>& shell,
                            std::vector<double>& out) {
  shell.clear();
  out.assign(targets.size(), std::numeric_limits<double>::infinity());
  search(source, targets, radius, shell_from, &shell, out, targets.size());
}

void GeodesicQuery::search(const SurfacePoint& source, const std::vector<SurfacePoint>& targets,
                           double radius, double shell_from,
                           std::vector<std::pair<std::uint32_t, double>>* shell,
                           std::vector<double>& out, std::size_t required) {
  if (!use_buckets_) {
    last_ = kHeap;
    if (anchored_) {
      run_anchored(heap_, source, targets, radius, shell_from, shell, out, required);
    } else {
      run(heap_, source, targets, radius, shell_from, shell, out, required);
    }
  } else if (anchored_) {
    if (!float_buckets_) float_buckets_ = std::make_unique<FloatBucketQueue>(g_);
    last_ = kFloatBuckets;
    run_anchored(*float_buckets_, source, targets, radius, shell_from, shell, out, required);
  } else {
    if (!buckets_) buckets_ = std::make_unique<BucketQueue>(g_);
    last_ = kBuckets;
    run(*buckets_, source, targets, radius, shell_from, shell, out, required);
  }
}

void GeodesicQuery::index_targets(const std::vector<SurfacePoint>& targets) {
  target_next_.assign(targets.size(), -1);
  target_done_.assign(targets.size(), 0);
  target_faces_.assign((g_.mesh().faces.size() + 63) / 64, 0);
  // note: each face's list runs from its last target to its first.
  face_heads_.clear();
  for (std::size_t j = 0; j < targets.size(); ++j) {
    target_faces_[targets[j].face >> 6] |= std::uint64_t{1} << (targets[j].face & 63);
    face_heads_.emplace_back(targets[j].face, static_cast<std::int32_t>(j));
  }
  std::stable_sort(face_heads_.begin(), face_heads_.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::size_t heads = 0;
  for (std::size_t i = 0; i < face_heads_.size(); ++i) {
    const bool last =
        i + 1 == face_heads_.size() || face_heads_[i + 1].first != face_heads_[i].first;
    const bool first = i == 0 || face_heads_[i - 1].first != face_heads_[i].first;
    target_next_[static_cast<std::size_t>(face_heads_[i].second)] =
        first ? -1 : face_heads_[i - 1].second;
    if (last) face_heads_[heads++] = face_heads_[i];
  }
  face_heads_.resize(heads);
}

std::int32_t GeodesicQuery::first_target(std::uint32_t f) const {
  const auto it =
      std::lower_bound(face_heads_.begin(), face_heads_.end(), f,
                       [](const auto& h, std::uint32_t face) { return h.first < face; });
  return it != face_heads_.end() && it->first == f ? it->second : -1;
}

template <typename Queue>
void GeodesicQuery::settle_target(Queue& queue, std::size_t j, std::size_t required,
                                  std::size_t& remaining) {
  // note: a target's last segment may be shorter than the bucket width, so another node of
  // this bucket may still lower it: it stays open for that, counted once.
  queue.reopen(static_cast<std::uint32_t>(g_.node_count() + j));
  if (!target_done_[j]) {
    target_done_[j] = 1;
    if (j < required && --remaining == 0) queue.finish();
  }
}

template <typename Queue>
void GeodesicQuery::prefetch_ahead(const Queue& queue) const {
  // The next node to settle, most likely: its records load while this one relaxes.
  // note: in a bucket the order is known several nodes ahead: their labels and positions are
  // fetched five nodes ahead, their edge or corner records (found through the position
  // record) and anchor three ahead, and the records of the nodes the next one will relax one
  // ahead (through its edge or corner record). (Three and two ahead left the settled node's
  // edge record a miss: T's searches on San Gabriel took 9 % longer, 3 alternated pairs.)
  const std::size_t n = g_.node_count(), nv = g_.mesh().vertex_count();
  const std::uint32_t next = queue.next_hint(0);
  if (next < n) {
    g_.for_each_neighbour_hint(next, [&](std::uint32_t v) {
      g_.prefetch_position(v);
      queue.prefetch_label(v);
      if (anchored_ && v >= nv) __builtin_prefetch(&anchors_[v - nv]);
    });
  }
  const std::uint32_t mid = queue.next_hint(2);
  if (mid < n) {
    g_.prefetch(mid);
    if (anchored_ && mid >= nv) __builtin_prefetch(&anchors_[mid - nv]);
  }
  const std::uint32_t later = queue.next_hint(4);
  if (later < n) {
    g_.prefetch_position(later);
    queue.prefetch_label(later);
  }
}

template <typename Queue>
void GeodesicQuery::collect_targets(const Queue& queue, const std::vector<SurfacePoint>& targets,
                                    std::vector<double>& out) {
  // note: a target not settled (search bounded by a radius, or unreachable) stays at infinity.
  const std::size_t n = g_.node_count();
  for (std::size_t j = 0; j < targets.size(); ++j) {
    if (target_done_[j]) out[j] = std::fabs(queue.dist(static_cast<std::uint32_t>(n + j)));
  }
}

template <typename Queue, typename Relax>
void GeodesicQuery::settle(Queue& queue, double radius, double shell_from,
                           std::vector<std::pair<std::uint32_t, double>>* shell,
                           std::size_t required, Relax&& relax) {
  const std::size_t n = g_.node_count();
  std::size_t remaining = required;
  LabelHeap::Entry top;
  settled_ = 0;
  while (queue.pop(top)) {
    const double d = top.key;
    const std::uint32_t u = top.node;
    if (u >= n) {
      settle_target(queue, u - n, required, remaining);
      continue;
    }
    prefetch_ahead(queue);
    ++settled_;
    // note: a node past the radius is settled too: it only ends the search sooner.
    if (d > radius) queue.finish();
    if (shell && d > shell_from) shell->emplace_back(u, d);
    relax(u, d, top.tag);
  }
}

template <typename Queue>
void GeodesicQuery::run(Queue& queue, const SurfacePoint& source,
                        const std::vector<SurfacePoint>& targets, double radius, double shell_from,
                        std::vector<std::pair<std::uint32_t, double>>* shell,
                        std::vector<double>& out, std::size_t required) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::size_t n = g_.node_count();
  // Targets are extra nodes n + j, reached from their face's boundary nodes.
  index_targets(targets);
  queue.reset(n + targets.size());
  const double src[3] = {source.x, source.y, source.z};
  // Relaxes from a point p at distance d into face f: its boundary nodes and its targets.
  // note: a node improves only if |p v| < dist(v) - d; comparing squares first skips the
  // square root for the many relaxations that cannot improve (settled or nearer nodes).
  auto relax = [&](std::uint32_t v, const double* p, const double* q, double d, std::uint32_t via,
                   std::uint32_t from) {
    const double old = queue.dist(v);
    const double gap = old - d;
    if (!(gap > 0)) return;
    const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
    const double w2 = dx * dx + dy * dy + dz * dz;
    if (w2 >= gap * gap) return;
    const double nd = d + std::sqrt(w2);
    if (nd < old) {
      if (old == inf && v < n) g_.prefetch(v);
      queue.decrease(v, nd, via, from);
    }
  };
  auto relax_targets = [&](std::uint32_t f, const double* p, double d, std::uint32_t from) {
    if (!(target_faces_[f >> 6] >> (f & 63) & 1)) return;
    for (std::int32_t j = first_target(f); j >= 0; j = target_next_[j]) {
      const double q[3] = {targets[j].x, targets[j].y, targets[j].z};
      relax(static_cast<std::uint32_t>(n + j), p, q, d, SteinerGraph::kAnywhere, from);
    }
  };
  // The source's face: its boundary nodes and targets, from the source point itself.
  g_.face_nodes(source.face, nodes_);
  for (std::uint32_t v : nodes_) relax(v, src, g_.position(v), 0.0, source.face, LabelHeap::kNone);
  relax_targets(source.face, src, 0.0, LabelHeap::kNone);
  settle(queue, radius, shell_from, shell, required,
         [&](std::uint32_t u, double d, std::uint32_t tag) {
           const double* p = g_.position(u);
           g_.for_each_neighbour(
               u, tag,
               [&](std::uint32_t v, std::uint32_t via) { relax(v, p, g_.position(v), d, via, u); },
               [&](std::uint32_t f) { relax_targets(f, p, d, u); });
         });
  collect_targets(queue, targets, out);
}

// The anchored search: Dijkstra on the same graph, where a label is a straight segment from an
// anchor point (the source, a vertex, or the node where the path last bent) unfolded across the
// faces crossed so far, as in any-angle path planning (Theta*: Nash, Daniel, Koenig and Felner,
// "Theta*: any-angle path planning on grids", AAAI 2007) carried onto a surface with the window
// of Chen and Han ("Shortest paths on a polyhedron", SoCG 1990): each label keeps the part of
// its node's edge the anchor sees through every edge crossed, and a node beyond sees the anchor
// exactly when its segment from the anchor passes through that part. One label per node (the
// shortest), so a window another label would have carried is lost and the path bends at a
// graph node there instead: the distances are those of real surface paths, much nearer the
// geodesic than the graph's own (which bend at every edge), so far fewer Steiner points find the
// shortest route among near ties; the path is then pulled taut exactly (geodesic_path.hpp).
// This class holds one search's relaxations: start() from the source, relax() per settled node.
template <typename Queue>
class GeodesicQuery::Anchored {
 public:
  Anchored(GeodesicQuery& q, Queue& queue, const std::vector<SurfacePoint>& targets)
      : q_(q),
        g_(q.g_),
        queue_(queue),
        targets_(targets),
        n_(g_.node_count()),
        nv_(static_cast<std::uint32_t>(g_.mesh().vertex_count())) {}

  // The source's face: its boundary nodes and targets, straight from the source.
  void start(const SurfacePoint& source) {
    const double src[3] = {source.x, source.y, source.z};
    const P3 s3 = pt(src);
    g_.face_nodes(source.face, q_.nodes_);
    for (std::uint32_t v : q_.nodes_) {
      const P3 v3 = pt(g_.position(v));
      if (improve(v, norm(sub(v3, s3)), source.face, LabelHeap::kNone)) {
        set_anchor(v, v3, s3);
        set_bend(v, LabelHeap::kNone);
      }
    }
    cx_.straight = false;
    relax_targets(source.face, src, 0.0, LabelHeap::kNone);
  }

  // The relaxations from settled node u at distance d, its label having come through `tag`.
  [[gnu::flatten]] void relax(std::uint32_t u, double d, std::uint32_t tag) {
    const double* up = g_.position(u);
    const P3 u3 = pt(up);
    std::uint32_t face = SteinerGraph::kNoFace;  // the face cx_ is set up for
    cx_.straight = false;
    g_.for_each_neighbour(
        u, tag, [&](std::uint32_t v, std::uint32_t via) { relax_node(u, up, u3, d, v, via, face); },
        [&](std::uint32_t f) {
          if (u >= nv_ && f != face) {
            cross_into(u, up, d, f);
            face = f;
          }
          relax_targets(f, up, d, u);
        });
  }

 private:
  struct P3 {
    double x, y, z;
  };
  static P3 pt(const double* p) { return P3{p[0], p[1], p[2]}; }
  static P3 sub(P3 a, P3 b) { return P3{a.x - b.x, a.y - b.y, a.z - b.z}; }
  static double dot(P3 a, P3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
  static double norm(P3 a) { return std::sqrt(dot(a, a)); }
  static constexpr double kInf = std::numeric_limits<double>::infinity();

  static bool has_anchor(const Anchor& an) { return an.lo <= an.hi; }
  // A window's ends as stored (fractions of the edge, rounded outwards) and back.
  static constexpr double kWindowSteps = 65535.0;
  // note: the clamped value is in [0, 65535], where truncation is floor: a conversion, not a
  // call of floor or ceil (no SSE4.1 in the default build), the same values.
  static std::uint16_t window_lo(double f) {
    return static_cast<std::uint16_t>(std::clamp(f * kWindowSteps, 0.0, kWindowSteps));
  }
  static std::uint16_t window_hi(double f) {
    const double x = std::clamp(f * kWindowSteps, 0.0, kWindowSteps);
    const auto t = static_cast<std::uint16_t>(x);
    return static_cast<std::uint16_t>(t + (t < x));
  }
  static double fraction(std::uint16_t q) { return q / kWindowSteps; }
  // Node v (at v3) gets anchor point a (offsets from v).
  static void place(Anchor& an, P3 v3, P3 a) {
    an.off[0] = static_cast<float>(a.x - v3.x);
    an.off[1] = static_cast<float>(a.y - v3.y);
    an.off[2] = static_cast<float>(a.z - v3.z);
  }
  // A Steiner node's anchor record (vertices have none: a path through one bends there).
  Anchor& anchor(std::uint32_t v) const { return q_.anchors_[v - nv_]; }
  // The anchor point of Steiner node u (at up).
  P3 anchor_of(std::uint32_t u, const double* up) const {
    const Anchor& an = anchor(u);
    return P3{up[0] + an.off[0], up[1] + an.off[1], up[2] + an.off[2]};
  }
  // The distance of anchor point a of a node at p3, at distance d: the node's less the segment.
  static double anchor_dist(P3 p3, P3 a, double d) { return d - norm(sub(p3, a)); }
  // Node v (at v3) bends: its anchor is point a, seen through v's whole edge.
  void set_anchor(std::uint32_t v, P3 v3, P3 a) {
    if (v < nv_) return;
    Anchor& an = anchor(v);
    place(an, v3, a);
    an.lo = 0;
    an.hi = static_cast<std::uint16_t>(kWindowSteps);
  }
  bool improve(std::uint32_t v, double nd, std::uint32_t via, std::uint32_t from) {
    nd = Queue::key(nd);
    const double old = queue_.dist(v);
    if (!(nd < old) || queue_.settled_dist(v) < kInf) return false;
    if (old == kInf && v < n_) g_.prefetch(v);
    queue_.decrease(v, nd, via, from);
    return true;
  }
  // With tracking, the bend of node v's new label (GeodesicQuery::bend()).
  void set_bend(std::uint32_t v, std::uint32_t bend) {
    if (!q_.track_bends_) return;
    (v < nv_ ? q_.vertex_bends_[v] : anchor(v).bend) = bend;
  }
  // The bend of a node reached straight from u's anchor (u at distance d, the node at nd): u's,
  // or u itself where it is the node last before a waypoint (with tracking; else none).
  std::uint32_t bend_of(std::uint32_t u, double d, double nd) const {
    if (!q_.track_bends_) return LabelHeap::kNone;
    const double per = q_.per_waypoint_;
    // note: floor by conversion (distances are non-negative, and far fewer than 2^63 waypoints
    // apart): the same test without two calls of floor.
    if (per > 0 && static_cast<std::int64_t>(nd * per) != static_cast<std::int64_t>(d * per)) {
      return u;
    }
    return q_.bend(u);
  }

  // Relaxing across a Steiner node's edge (a, b) into face f (corner o): a frame in f's plane
  // (origin a, ex along the edge, ny towards o), o at (so, yo), the anchor unfolded to
  // (sa, -h) (h > 0: behind the edge), and its window [lo, hi] on the edge.
  struct Crossing {
    P3 a, ex, ny, anchor;
    std::uint32_t ia = 0, ib = 0, io = 0;
    double len = 0, so = 0, yo = 0, ao = 0, bo = 0;
    double sa = 0, h = 0, da = 0, lo = 0, hi = -1;
    bool straight = false;
  };

  // Sets cx_ up for node u (a Steiner point, at up, at distance d) crossing into face f;
  // cx_.straight: u has an anchor behind the edge to carry.
  void cross_into(std::uint32_t u, const double* up, double d, std::uint32_t f) {
    Crossing& cx = cx_;
    cx.straight = false;
    const auto ends = g_.node_edge_ends(u);
    cx.ia = ends[0];
    cx.ib = ends[1];
    // note: from u's edge record, which the search has just read, not from the face's corners.
    cx.io = g_.opposite(u, f);
    cx.a = pt(g_.position(ends[0]));
    const P3 e = sub(pt(g_.position(ends[1])), cx.a);
    cx.len = norm(e);
    cx.ex = {e.x / cx.len, e.y / cx.len, e.z / cx.len};
    const P3 ao = sub(pt(g_.position(cx.io)), cx.a);
    cx.so = dot(ao, cx.ex);
    const P3 ny{ao.x - cx.so * cx.ex.x, ao.y - cx.so * cx.ex.y, ao.z - cx.so * cx.ex.z};
    cx.yo = norm(ny);
    if (!(cx.yo > 1e-12 * cx.len)) return;
    cx.ny = {ny.x / cx.yo, ny.y / cx.yo, ny.z / cx.yo};
    // note: not std::hypot, several times slower; the lengths are far from overflow.
    cx.ao = std::sqrt(cx.so * cx.so + cx.yo * cx.yo);
    cx.bo = std::sqrt((cx.so - cx.len) * (cx.so - cx.len) + cx.yo * cx.yo);
    const Anchor& an = anchor(u);
    if (!has_anchor(an)) return;
    const P3 A = anchor_of(u, up);
    const P3 r = sub(A, cx.a);
    cx.sa = dot(r, cx.ex);
    const P3 perp{r.x - cx.sa * cx.ex.x, r.y - cx.sa * cx.ex.y, r.z - cx.sa * cx.ex.z};
    cx.h = norm(perp);
    // note: an anchor on the face's own side (or on the edge's line) does not look through it.
    if (!(cx.h > 1e-9 * cx.len) || dot(perp, cx.ny) > 0) return;
    cx.anchor = {cx.a.x + cx.sa * cx.ex.x - cx.h * cx.ny.x,
                 cx.a.y + cx.sa * cx.ex.y - cx.h * cx.ny.y,
                 cx.a.z + cx.sa * cx.ex.z - cx.h * cx.ny.z};
    cx.da = anchor_dist(pt(up), A, d);
    const double tol = 1e-7 * cx.len;
    cx.lo = fraction(an.lo) * cx.len - tol;
    cx.hi = fraction(an.hi) * cx.len + tol;
    cx.straight = true;
  }
  // Where the segment from cx_'s anchor to the point at (sp, yp) in cx_'s frame crosses the
  // edge.
  double crossing2(double sp, double yp) const {
    return cx_.sa + (sp - cx_.sa) * cx_.h / (cx_.h + yp);
  }
  // p in cx_'s frame, and where its segment from the anchor crosses the edge.
  double crossing(P3 p, double& sp, double& yp) const {
    const P3 ap = sub(p, cx_.a);
    sp = dot(ap, cx_.ex);
    yp = std::max(0.0, dot(ap, cx_.ny));
    return crossing2(sp, yp);
  }
  // Node v (at v3, at (sv, yv) in cx_'s frame, a Steiner point on edge (a, o) or (b, o) of the
  // crossed face) is reached straight from cx_'s anchor: the part of its edge the anchor sees
  // through cx_'s window. note: from the face's corners alone, no other record is read.
  void carry(std::uint32_t v, P3 v3, double sv, double yv) {
    const Crossing& cx = cx_;
    if (v < nv_) return;
    Anchor& an = anchor(v);
    // Its edge: the one v is nearer the line of; its ends in id order (as the graph keeps them).
    const double off_ao = std::fabs(sv * cx.yo - yv * cx.so) / cx.ao;
    const double off_bo = std::fabs((sv - cx.len) * cx.yo - yv * (cx.so - cx.len)) / cx.bo;
    const bool on_ao = off_ao <= off_bo;
    const std::uint32_t other = on_ao ? cx.ia : cx.ib;
    const double other_s = on_ao ? 0.0 : cx.len;
    double s0 = other_s, y0 = 0, s1 = cx.so, y1 = cx.yo;
    if (cx.io < other) {
      std::swap(s0, s1);
      std::swap(y0, y1);
    }
    const double c0 = crossing2(s0, y0), c1 = crossing2(s1, y1);
    auto solve = [&](double c) {
      const double den = (s1 - s0) * cx.h - (c - cx.sa) * (y1 - y0);
      const double t = ((c - cx.sa) * (cx.h + y0) - (s0 - cx.sa) * cx.h) / den;
      return std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
    };
    double tlo, thi;
    if (c0 <= c1) {
      tlo = cx.lo <= c0 ? 0.0 : cx.lo >= c1 ? 1.0 : solve(cx.lo);
      thi = cx.hi >= c1 ? 1.0 : cx.hi <= c0 ? 0.0 : solve(cx.hi);
    } else {
      tlo = cx.hi >= c0 ? 0.0 : cx.hi <= c1 ? 1.0 : solve(cx.hi);
      thi = cx.lo <= c1 ? 1.0 : cx.lo >= c0 ? 0.0 : solve(cx.lo);
    }
    place(an, v3, cx.anchor);
    an.lo = window_lo(std::min(tlo, thi));
    an.hi = window_hi(std::max(tlo, thi));
  }
  // The distance to point p through cx_ (or bent at u, at distance d).
  double through(const double* up, double d, P3 p) const {
    if (cx_.straight) {
      double sp, yp;
      const double c = crossing(p, sp, yp);
      if (c >= cx_.lo && c <= cx_.hi) return cx_.da + norm(sub(p, cx_.anchor));
    }
    return d + norm(sub(p, pt(up)));
  }
  // The targets in face f, through cx_ where it is set up for f (a Steiner node's crossing),
  // else bent at up.
  void relax_targets(std::uint32_t f, const double* up, double d, std::uint32_t from) {
    if (!(q_.target_faces_[f >> 6] >> (f & 63) & 1)) return;
    for (std::int32_t j = q_.first_target(f); j >= 0; j = q_.target_next_[j]) {
      const P3 p{targets_[j].x, targets_[j].y, targets_[j].z};
      const double nd = Queue::key(through(up, d, p));
      const auto v = static_cast<std::uint32_t>(n_ + j);
      const double old = queue_.dist(v);
      if (nd < old && !q_.target_done_[j]) queue_.decrease(v, nd, SteinerGraph::kAnywhere, from);
    }
  }
  // v (at v3, tentatively at old) bent at u (at u3, distance d): straight from u, which becomes
  // v's anchor. note: comparing squares first skips the square root where v cannot improve.
  void bent(std::uint32_t u, P3 u3, double d, std::uint32_t v, P3 v3, double old,
            std::uint32_t via) {
    const P3 uv = sub(v3, u3);
    const double w2 = dot(uv, uv), gap = old - d;
    if (!(gap > 0) || w2 >= gap * gap) return;
    if (improve(v, d + std::sqrt(w2), via, u)) {
      set_anchor(v, v3, u3);
      set_bend(v, u);
    }
  }
  // Graph node v joined to settled node u through face `via` (or along u's edge): straight from
  // u's anchor where the window lets it, else bent at u. `face`: the face cx_ is set up for.
  void relax_node(std::uint32_t u, const double* up, P3 u3, double d, std::uint32_t v,
                  std::uint32_t via, std::uint32_t& face) {
    // note: a settled node (negative in the buckets) or one at distance 0 cannot improve:
    // skipped before its position is read.
    const double old = queue_.dist(v);
    if (!(old > 0)) return;
    const P3 v3 = pt(g_.position(v));
    if (via == SteinerGraph::kAlongEdge) {
      // Along u's own edge: straight from u's anchor where its window holds v.
      if (u >= nv_ && has_anchor(anchor(u))) {
        const Anchor& an = anchor(u);
        // note: the window in fractions of the edge, which v's place along it is exactly.
        const double fv = g_.edge_fraction(u, v);
        constexpr double tol = 1e-7;
        if (fv >= fraction(an.lo) - tol && fv <= fraction(an.hi) + tol) {
          const P3 A = anchor_of(u, up);
          const double da = anchor_dist(u3, A, d);
          const double nd = da + norm(sub(v3, A));
          const std::uint32_t bend = bend_of(u, d, nd);
          if (improve(v, nd, via, u)) {
            if (v >= nv_) {
              Anchor& av = anchor(v);
              av.lo = an.lo;
              av.hi = an.hi;
              place(av, v3, A);
            }
            set_bend(v, bend);
          }
          return;
        }
      }
      return bent(u, u3, d, v, v3, old, via);
    }
    if (u < nv_) return bent(u, u3, d, v, v3, old, via);
    if (via != face) {
      cross_into(u, up, d, via);
      face = via;
    }
    if (cx_.straight) {
      const P3 av = sub(v3, cx_.anchor);
      // note: a node no nearer than the anchor's straight segment could bring is skipped: the
      // segment bent at u is never shorter.
      const double w2 = dot(av, av), gap = old - cx_.da;
      if (!(gap > 0) || w2 >= gap * gap) return;
      double sp, yp;
      const double c = crossing(v3, sp, yp);
      if (c >= cx_.lo && c <= cx_.hi) {
        const double nd = cx_.da + std::sqrt(w2);
        if (improve(v, nd, via, u)) {
          carry(v, v3, sp, yp);
          set_bend(v, bend_of(u, d, nd));
        }
        return;
      }
    }
    bent(u, u3, d, v, v3, old, via);
  }

  GeodesicQuery& q_;
  const SteinerGraph& g_;
  Queue& queue_;
  const std::vector<SurfacePoint>& targets_;
  const std::size_t n_;
  const std::uint32_t nv_;
  Crossing cx_;
};

template <typename Queue>
void GeodesicQuery::run_anchored(Queue& queue, const SurfacePoint& source,
                                 const std::vector<SurfacePoint>& targets, double radius,
                                 double shell_from,
                                 std::vector<std::pair<std::uint32_t, double>>* shell,
                                 std::vector<double>& out, std::size_t required) {
  const std::size_t n = g_.node_count();
  // note: Steiner nodes only (a vertex has no anchor).
  const std::size_t steiner = g_.steiner_count();
  if (anchors_.size() != steiner) anchors_.resize(steiner);
  // note: no reset: a node's bend is written with every label it gets, read only once reached.
  if (track_bends_ && vertex_bends_.size() != n - steiner) vertex_bends_.resize(n - steiner);
  if (!track_bends_) vertex_bends_ = HugeVector<std::uint32_t>();
  index_targets(targets);
  queue.reset(n + targets.size());
  Anchored<Queue> search(*this, queue, targets);
  search.start(source);
  settle(queue, radius, shell_from, shell, required,
         [&](std::uint32_t u, double d, std::uint32_t tag) { search.relax(u, d, tag); });
  collect_targets(queue, targets, out);
}

void GeodesicQuery::path(std::size_t target, std::vector<std::uint32_t>& nodes) const {
  nodes.clear();
  const std::uint32_t first = pred(static_cast<std::uint32_t>(g_.node_count() + target));
  if (first != LabelHeap::kNone) path_to_node(first, nodes);
}

void GeodesicQuery::path_to_node(std::uint32_t node, std::vector<std::uint32_t>& nodes) const {
  nodes.clear();
  // note: a settled node's predecessor was settled before it, so the chain ends at the source.
  for (std::uint32_t v = node; v != LabelHeap::kNone; v = pred(v)) nodes.push_back(v);
  std::reverse(nodes.begin(), nodes.end());
}

}  // namespace dpts::core

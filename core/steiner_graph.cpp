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
std::vector<std::tuple<std::uint64_t, std::uint32_t, int>> sorted_face_edges(const TriMesh& m) {
  std::vector<std::tuple<std::uint64_t, std::uint32_t, int>> e;
  e.reserve(3 * m.faces.size());
  for (std::uint32_t f = 0; f < m.faces.size(); ++f) {
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = m.faces[f][i], b = m.faces[f][(i + 1) % 3];
      e.emplace_back((std::uint64_t{std::min(a, b)} << 32) | std::max(a, b), f, i);
    }
  }
  std::sort(e.begin(), e.end());
  return e;
}

}  // namespace

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
  if (!(delta > 0)) throw std::invalid_argument("Steiner spacing delta must be positive");
  const std::size_t nv = mesh.vertex_count();
  face_edges_.resize(mesh.faces.size());
  const auto e = sorted_face_edges(mesh);
  // Count the nodes before allocating any: a mesh far larger than delta (or with a non-finite
  // coordinate) is refused here, not by running out of memory.
  double nodes = static_cast<double>(nv);
  std::size_t edge_count = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (i > 0 && std::get<0>(e[i]) == std::get<0>(e[i - 1])) continue;
    ++edge_count;
    const std::uint64_t key = std::get<0>(e[i]);
    nodes += std::floor(dist3(&mesh.xyz[3 * (key >> 32)], &mesh.xyz[3 * (key & 0xFFFFFFFFu)]) /
                        delta);
  }
  if (!(nodes < static_cast<double>(kMaxNodes))) {
    throw std::invalid_argument("too many Steiner points (" + std::to_string(nodes) +
                                "; at most " + std::to_string(kMaxNodes) + ")");
  }
  nodes_.reserve(static_cast<std::size_t>(nodes));
  for (std::size_t v = 0; v < nv; ++v) {
    nodes_.push_back({{mesh.xyz[3 * v], mesh.xyz[3 * v + 1], mesh.xyz[3 * v + 2]}, kNoEdge});
  }
  edges_.reserve(edge_count);
  edge_first_.reserve(edge_count + 1);
  edge_first_.push_back(static_cast<std::uint32_t>(nv));
  for (std::size_t i = 0; i < e.size();) {
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
    rec.ends = {static_cast<std::uint32_t>(key >> 32), static_cast<std::uint32_t>(key & 0xFFFFFFFFu)};
    for (int side = 0; side < 2; ++side) rec.sides[side].face = faces[side];
    edges_.push_back(rec);
    // floor(len / delta) points evenly inside the edge.
    const double* a = &mesh.xyz[3 * (key >> 32)];
    const double* b = &mesh.xyz[3 * (key & 0xFFFFFFFFu)];
    const auto k = static_cast<std::uint32_t>(std::floor(dist3(a, b) / delta));
    for (std::uint32_t j = 1; j <= k; ++j) {
      const double t = static_cast<double>(j) / (k + 1);
      nodes_.push_back({{a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]),
                         a[2] + t * (b[2] - a[2])},
                        edge});
    }
    edge_first_.push_back(static_cast<std::uint32_t>(nodes_.size()));
  }
  // Each edge's record: its nodes, and per face the opposite corner and the other two edges.
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
  // Vertex -> its corners, CSR.
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

void SteinerGraph::face_nodes(std::uint32_t f, std::vector<std::uint32_t>& out) const {
  out.clear();
  for (int i = 0; i < 3; ++i) out.push_back(mesh_.faces[f][i]);
  for (int i = 0; i < 3; ++i) {
    const std::uint32_t e = face_edges_[f][i];
    for (std::uint32_t n = edge_first_[e]; n < edge_first_[e + 1]; ++n) out.push_back(n);
  }
}

void LabelHeap::reset(std::size_t nodes) {
  heap_.clear();
  label_.assign(nodes, {std::numeric_limits<double>::infinity(), 0});
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

void LabelHeap::decrease(std::uint32_t node, double key, std::uint32_t tag) {
  Label& l = label_[node];
  l.dist = key;
  if (l.slot == 0) {
    heap_.push_back({key, node, tag});
    sift_up(heap_.size() - 1, {key, node, tag});
  } else {
    sift_up(l.slot - 1, {key, node, tag});
  }
}

LabelHeap::Entry LabelHeap::pop() {
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
  return top;
}

GeodesicQuery::GeodesicQuery(const SteinerGraph& graph)
    : g_(graph), face_target_head_(graph.mesh().faces.size(), -1) {}

void GeodesicQuery::distances(const SurfacePoint& source, const std::vector<SurfacePoint>& targets,
                              std::vector<double>& out) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::size_t n = g_.node_count();
  out.assign(targets.size(), inf);
  if (targets.empty()) return;
  // Targets are extra nodes n + j, reached from their face's boundary nodes.
  target_next_.assign(targets.size(), -1);
  for (std::size_t j = 0; j < targets.size(); ++j) {
    target_next_[j] = face_target_head_[targets[j].face];
    face_target_head_[targets[j].face] = static_cast<std::int32_t>(j);
  }
  labels_.reset(n + targets.size());
  const double src[3] = {source.x, source.y, source.z};
  // Relaxes from a point p at distance d into face f: its boundary nodes and its targets.
  // note: a node improves only if |p v| < dist(v) - d; comparing squares first skips the
  // square root for the many relaxations that cannot improve (settled or nearer nodes).
  auto relax = [&](std::uint32_t v, const double* p, const double* q, double d,
                   std::uint32_t via) {
    const double old = labels_.dist(v);
    const double gap = old - d;
    if (!(gap > 0)) return;
    const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
    const double w2 = dx * dx + dy * dy + dz * dz;
    if (w2 >= gap * gap) return;
    const double nd = d + std::sqrt(w2);
    if (nd < old) {
      if (old == inf && v < n) g_.prefetch(v);
      labels_.decrease(v, nd, via);
    }
  };
  auto relax_targets = [&](std::uint32_t f, const double* p, double d) {
    for (std::int32_t j = face_target_head_[f]; j >= 0; j = target_next_[j]) {
      const double q[3] = {targets[j].x, targets[j].y, targets[j].z};
      relax(static_cast<std::uint32_t>(n + j), p, q, d, SteinerGraph::kAnywhere);
    }
  };
  auto relax_face = [&](std::uint32_t f, const double* p, double d) {
    g_.face_nodes(f, nodes_);
    for (std::uint32_t v : nodes_) relax(v, p, g_.position(v), d, f);
    relax_targets(f, p, d);
  };
  relax_face(source.face, src, 0.0);
  std::size_t remaining = targets.size();
  while (!labels_.empty() && remaining > 0) {
    const LabelHeap::Entry top = labels_.pop();
    const double d = top.key;
    const std::uint32_t u = top.node;
    // The next node to settle, most likely: its records load while this one relaxes.
    if (!labels_.empty() && labels_.top_node() < n) g_.prefetch(labels_.top_node());
    if (u >= n) {
      out[u - n] = d;
      --remaining;
      continue;
    }
    const double* p = g_.position(u);
    g_.for_each_neighbour(
        u, top.tag,
        [&](std::uint32_t v, std::uint32_t via) { relax(v, p, g_.position(v), d, via); },
        [&](std::uint32_t f) { relax_targets(f, p, d); });
  }
  for (const auto& t : targets) face_target_head_[t.face] = -1;
}

}  // namespace dpts::core

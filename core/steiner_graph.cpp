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
  for (std::size_t i = 0; i < e.size(); ++i) {
    if (i > 0 && std::get<0>(e[i]) == std::get<0>(e[i - 1])) continue;
    const std::uint64_t key = std::get<0>(e[i]);
    nodes += std::floor(dist3(&mesh.xyz[3 * (key >> 32)], &mesh.xyz[3 * (key & 0xFFFFFFFFu)]) /
                        delta);
  }
  if (!(nodes < static_cast<double>(kMaxNodes))) {
    throw std::invalid_argument("too many Steiner points (" + std::to_string(nodes) +
                                "; at most " + std::to_string(kMaxNodes) + ")");
  }
  pos_.reserve(3 * static_cast<std::size_t>(nodes));
  pos_.assign(mesh.xyz.begin(), mesh.xyz.end());
  edge_first_.push_back(static_cast<std::uint32_t>(nv));
  for (std::size_t i = 0; i < e.size();) {
    const std::uint64_t key = std::get<0>(e[i]);
    const std::uint32_t edge = static_cast<std::uint32_t>(edge_faces_.size());
    std::array<std::uint32_t, 2> faces{kNoFace, kNoFace};
    int n = 0;
    for (; i < e.size() && std::get<0>(e[i]) == key; ++i, ++n) {
      if (n >= 2) throw std::invalid_argument("mesh has an edge shared by more than two faces");
      faces[n] = std::get<1>(e[i]);
      face_edges_[std::get<1>(e[i])][std::get<2>(e[i])] = edge;
    }
    edge_faces_.push_back(faces);
    edge_ends_.push_back(
        {static_cast<std::uint32_t>(key >> 32), static_cast<std::uint32_t>(key & 0xFFFFFFFFu)});
    // floor(len / delta) points evenly inside the edge.
    const double* a = &mesh.xyz[3 * (key >> 32)];
    const double* b = &mesh.xyz[3 * (key & 0xFFFFFFFFu)];
    const auto k = static_cast<std::uint32_t>(std::floor(dist3(a, b) / delta));
    for (std::uint32_t j = 1; j <= k; ++j) {
      const double t = static_cast<double>(j) / (k + 1);
      for (int c = 0; c < 3; ++c) pos_.push_back(a[c] + t * (b[c] - a[c]));
      node_edge_.push_back(edge);
    }
    edge_first_.push_back(static_cast<std::uint32_t>(pos_.size() / 3));
  }
  // Vertex -> faces, CSR.
  vertex_face_first_.assign(nv + 1, 0);
  for (const auto& f : mesh.faces) {
    for (auto v : f) ++vertex_face_first_[v + 1];
  }
  for (std::size_t v = 0; v < nv; ++v) vertex_face_first_[v + 1] += vertex_face_first_[v];
  vertex_faces_.resize(vertex_face_first_[nv]);
  std::vector<std::uint32_t> fill(vertex_face_first_.begin(), vertex_face_first_.end() - 1);
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    for (auto v : mesh.faces[f]) vertex_faces_[fill[v]++] = f;
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

void NodeHeap::reset(std::size_t nodes) {
  heap_.clear();
  pos_.assign(nodes, 0);
}

void NodeHeap::sift_up(std::size_t i, Entry e) {
  while (i > 0) {
    const std::size_t parent = (i - 1) / 4;
    if (!(e.key < heap_[parent].key)) break;
    heap_[i] = heap_[parent];
    pos_[heap_[i].node] = static_cast<std::uint32_t>(i + 1);
    i = parent;
  }
  heap_[i] = e;
  pos_[e.node] = static_cast<std::uint32_t>(i + 1);
}

void NodeHeap::push_or_decrease(std::uint32_t node, double key) {
  const std::uint32_t p = pos_[node];
  if (p == 0) {
    heap_.push_back({key, node});
    sift_up(heap_.size() - 1, {key, node});
  } else {
    sift_up(p - 1, {key, node});
  }
}

std::pair<double, std::uint32_t> NodeHeap::pop() {
  const Entry top = heap_.front();
  pos_[top.node] = 0;
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
      pos_[heap_[i].node] = static_cast<std::uint32_t>(i + 1);
      i = best;
    }
    heap_[i] = last;
    pos_[last.node] = static_cast<std::uint32_t>(i + 1);
  }
  return {top.key, top.node};
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
  dist_.assign(n + targets.size(), inf);
  target_next_.assign(targets.size(), -1);
  for (std::size_t j = 0; j < targets.size(); ++j) {
    target_next_[j] = face_target_head_[targets[j].face];
    face_target_head_[targets[j].face] = static_cast<std::int32_t>(j);
  }
  heap_.reset(n + targets.size());
  const double src[3] = {source.x, source.y, source.z};
  // Relaxes from a point p at distance d into face f: its boundary nodes and its targets.
  // note: a node improves only if |p v| < dist(v) - d; comparing squares first skips the
  // square root for the many relaxations that cannot improve (settled or nearer nodes).
  auto relax = [&](std::uint32_t v, const double* p, const double* q, double d) {
    const double gap = dist_[v] - d;
    if (!(gap > 0)) return;
    const double dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
    const double w2 = dx * dx + dy * dy + dz * dz;
    if (w2 >= gap * gap) return;
    const double nd = d + std::sqrt(w2);
    if (nd < dist_[v]) {
      dist_[v] = nd;
      heap_.push_or_decrease(v, nd);
    }
  };
  auto relax_targets = [&](std::uint32_t f, const double* p, double d) {
    for (std::int32_t j = face_target_head_[f]; j >= 0; j = target_next_[j]) {
      const double q[3] = {targets[j].x, targets[j].y, targets[j].z};
      relax(static_cast<std::uint32_t>(n + j), p, q, d);
    }
  };
  auto relax_face = [&](std::uint32_t f, const double* p, double d) {
    g_.face_nodes(f, nodes_);
    for (std::uint32_t v : nodes_) relax(v, p, g_.position(v), d);
    relax_targets(f, p, d);
  };
  relax_face(source.face, src, 0.0);
  std::size_t remaining = targets.size();
  while (!heap_.empty() && remaining > 0) {
    // note: no structured binding: C++17 lambdas (clang) cannot capture one.
    const std::pair<double, std::uint32_t> top = heap_.pop();
    const double d = top.first;
    const std::uint32_t u = top.second;
    if (u >= n) {
      out[u - n] = d;
      --remaining;
      continue;
    }
    const double* p = g_.position(u);
    g_.for_each_neighbour(
        u, [&](std::uint32_t v) { relax(v, p, g_.position(v), d); },
        [&](std::uint32_t f) { relax_targets(f, p, d); });
  }
  for (const auto& t : targets) face_target_head_[t.face] = -1;
}

}  // namespace dpts::core

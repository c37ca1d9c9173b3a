// QSlim baseline: CGAL Garland-Heckbert edge collapse with a locked border and no folds.
#include "core/qslim.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Edge_collapse_visitor_base.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Constrained_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "core/errors.hpp"

namespace dpts::core {
namespace {

namespace SMS = CGAL::Surface_mesh_simplification;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
using VertexIndex = Mesh::Vertex_index;

// Border edges are constrained: never collapsed, and Constrained_placement keeps a border
// vertex where it is when its neighbour collapses onto it.
struct BorderMap {
  using key_type = Mesh::Edge_index;
  using value_type = bool;
  using reference = bool;
  using category = boost::readable_property_map_tag;
  const Mesh* mesh = nullptr;
  friend bool get(const BorderMap& m, key_type e) { return m.mesh->is_border(e); }
};

// Asks progress every 4096 calls (edges collected and popped alike): false throws
// Cancelled out of CGAL's collapse, whose mesh is then dropped.
struct Ticker {
  const Progress* progress = nullptr;
  std::size_t start = 0, keep = 0, calls = 0;
  void tick(std::size_t vertices) {
    if (++calls % 4096 != 0 || !progress || !*progress) return;
    const double done =
        start > keep ? static_cast<double>(start - std::max(vertices, keep)) / (start - keep) : 1;
    if (!(*progress)(done, "simplify")) throw Cancelled();
  }
};

// Stops at an exact vertex count.
struct VertexCountStop {
  const Mesh* mesh;
  std::size_t keep;
  template <typename F, typename Profile>
  bool operator()(const F&, const Profile&, std::size_t, std::size_t) const {
    return mesh->number_of_vertices() <= keep;
  }
};

// Ticks as the queue is collected (its costs take seconds on large meshes) and as edges are
// popped. (Not a wrapper of the cost: CGAL then no longer gives the Garland-Heckbert cost its
// quadric updates.)
struct TickingVisitor : SMS::Edge_collapse_visitor_base<Mesh> {
  const Mesh* mesh;
  Ticker* ticker;
  TickingVisitor(const Mesh* m, Ticker* t) : mesh(m), ticker(t) {}
  template <typename Profile, typename Cost>
  void OnCollected(const Profile&, const Cost&) {
    ticker->tick(mesh->number_of_vertices());
  }
  template <typename Profile, typename Cost>
  void OnSelected(const Profile&, const Cost&, std::size_t, std::size_t) {
    ticker->tick(mesh->number_of_vertices());
  }
};

// Rejects a collapse after which a triangle of the star would not be strictly
// counter-clockwise seen from above (a fold, or a sliver flat in x, y), and one that would
// move a border vertex (both ends on the border, joined by an interior edge).
struct NoFoldFilter {
  const Mesh* mesh;
  std::size_t* rejected;
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(
      const Profile& profile, boost::optional<typename Profile::Point> placement) const {
    if (!placement) return placement;
    if (mesh->is_border(profile.v0(), false) && mesh->is_border(profile.v1(), false)) {
      ++*rejected;
      return boost::none;
    }
    const auto& vpm = profile.vertex_point_map();
    const auto& triangles = profile.triangles();
    auto it = triangles.begin();
    // The first triangles are the edge's own faces, which the collapse removes.
    if (profile.left_face_exists()) ++it;
    if (profile.right_face_exists()) ++it;
    const K::Point_3& q = *placement;
    for (; it != triangles.end(); ++it) {
      // The second corner is the one that moves to the placement.
      const K::Point_3& p = get(vpm, it->v0);
      const K::Point_3& r = get(vpm, it->v2);
      if (CGAL::orientation(K::Point_2(p.x(), p.y()), K::Point_2(q.x(), q.y()),
                            K::Point_2(r.x(), r.y())) != CGAL::LEFT_TURN) {
        ++*rejected;
        return boost::none;
      }
    }
    return placement;
  }
};

}  // namespace

TriMesh qslim(const TriMesh& in, std::size_t keep, QslimStats* stats, const Progress& progress) {
  // note: building the mesh and its quadrics takes seconds on large meshes (tens under
  // sanitizers), before the first tick: a stop asked for meanwhile is honoured as they go.
  auto check = [&] {
    if (progress && !progress(0.0, "simplify")) throw Cancelled();
  };
  Mesh mesh;
  std::vector<VertexIndex> vi;
  vi.reserve(in.vertex_count());
  for (std::size_t v = 0; v < in.vertex_count(); ++v) {
    vi.push_back(mesh.add_vertex(K::Point_3(in.xyz[3 * v], in.xyz[3 * v + 1], in.xyz[3 * v + 2])));
  }
  for (std::size_t i = 0; i < in.faces.size(); ++i) {
    const auto& f = in.faces[i];
    if (mesh.add_face(vi[f[0]], vi[f[1]], vi[f[2]]) == Mesh::null_face()) {
      throw std::invalid_argument("qslim: the mesh is not a manifold surface");
    }
    if (i % 65536 == 65535) check();
  }
  check();
  QslimStats local;
  QslimStats& st = stats ? *stats : local;
  st.input_vertices = mesh.number_of_vertices();
  using Policies = SMS::GarlandHeckbert_plane_policies<Mesh, K>;
  Policies policies(mesh);
  check();
  const BorderMap border{&mesh};
  const SMS::Constrained_placement<Policies::Get_placement, BorderMap> placement(
      border, policies.get_placement());
  Ticker ticker{&progress, st.input_vertices, keep};
  SMS::edge_collapse(mesh, VertexCountStop{&mesh, keep},
                     CGAL::parameters::get_cost(policies.get_cost())
                         .visitor(TickingVisitor(&mesh, &ticker))
                         .get_placement(placement)
                         .edge_is_constrained_map(border)
                         .filter(NoFoldFilter{&mesh, &st.rejected_folds}));
  mesh.collect_garbage();
  TriMesh out;
  for (VertexIndex v : mesh.vertices()) {
    const K::Point_3& p = mesh.point(v);
    out.xyz.insert(out.xyz.end(), {p.x(), p.y(), p.z()});
  }
  for (Mesh::Face_index f : mesh.faces()) {
    std::array<std::uint32_t, 3> t{};
    int k = 0;
    for (VertexIndex v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) {
      t[k++] = static_cast<std::uint32_t>(v.idx());
    }
    out.faces.push_back(t);
  }
  st.kept_vertices = out.vertex_count();
  return out;
}

}  // namespace dpts::core

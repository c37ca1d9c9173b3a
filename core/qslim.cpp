// QSlim baseline: CGAL Garland-Heckbert edge collapse with a locked border and no folds.
#include "core/qslim.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Constrained_placement.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_triangle_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <cmath>
#include <stdexcept>
#include <vector>

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

// Whether v is an outline vertex that may go (Outline::kStraightRunsFree): on the border once,
// exactly collinear seen from above with its two border neighbours, and chord_ok (if set) lets
// the outline run straight between those.
bool straight_outline_vertex(const Mesh& mesh, VertexIndex v,
                             const std::function<bool(std::uint32_t, std::uint32_t)>& chord_ok) {
  Mesh::Halfedge_index in;  // the border halfedge into v
  int count = 0;
  for (Mesh::Halfedge_index h : CGAL::halfedges_around_target(mesh.halfedge(v), mesh)) {
    if (mesh.is_border(h)) {
      in = h;
      ++count;
    }
  }
  if (count != 1) return false;
  const K::Point_3& a = mesh.point(mesh.source(in));
  const K::Point_3& p = mesh.point(v);
  const K::Point_3& b = mesh.point(mesh.target(mesh.next(in)));
  if (CGAL::orientation(K::Point_2(a.x(), a.y()), K::Point_2(p.x(), p.y()),
                        K::Point_2(b.x(), b.y())) != CGAL::COLLINEAR) {
    return false;
  }
  // note: vertex indices are the input's (the mesh is not compacted until the end).
  return !chord_ok || chord_ok(static_cast<std::uint32_t>(mesh.source(in).idx()),
                               static_cast<std::uint32_t>(mesh.target(mesh.next(in)).idx()));
}

// Placement with a free outline: the quadric's optimum for an interior edge; a vertex on the
// outline never moves (an interior neighbour collapses onto it); an outline edge collapses
// onto one of its ends, the other one being a straight outline vertex, whichever costs less.
// note: an interior edge between two outline vertices would pinch the footprint: refused. So is
// any collapse at a vertex where the outline already pinches (two voids, or a void and the
// edge, touching at a corner): CGAL walks one fan of such a vertex only, and would take it for
// a plain outline vertex.
template <typename Placement, typename Cost>
struct OutlinePlacement {
  Placement base;
  Cost cost;
  const Mesh* mesh;
  const std::function<bool(std::uint32_t, std::uint32_t)>* chord_ok;
  const std::vector<char>* pinched;  // per input vertex
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile) const {
    if ((*pinched)[profile.v0().idx()] || (*pinched)[profile.v1().idx()]) return boost::none;
    const bool b0 = mesh->is_border(profile.v0(), true);
    const bool b1 = mesh->is_border(profile.v1(), true);
    if (!b0 && !b1) return base(profile);
    const bool outline_edge = profile.is_v0_v1_a_border() || profile.is_v1_v0_a_border();
    if (!outline_edge) {
      if (b0 && b1) return boost::none;
      return b0 ? profile.p0() : profile.p1();
    }
    boost::optional<typename Profile::Point> best;
    boost::optional<typename Profile::FT> best_cost;
    auto consider = [&](VertexIndex gone, const typename Profile::Point& stays) {
      if (!straight_outline_vertex(*mesh, gone, *chord_ok)) return;
      const auto c = cost(profile, boost::optional<typename Profile::Point>(stays));
      if (c && (!best_cost || *c < *best_cost)) {
        best = stays;
        best_cost = c;
      }
    };
    consider(profile.v0(), profile.p1());
    consider(profile.v1(), profile.p0());
    return best;
  }
};

// The quadric cost plus weight x (change of the star's 3D surface area)^2: a collapse that
// flattens or roughens the surface (so shortens or lengthens the paths across it) costs more,
// where the quadrics see only distances to planes. Both terms are in metres^4, so the weight
// does not depend on the DEM's scale. The default-mode issue's lever "an objective that sees
// lengths or area"; weight 100 measured best of 0, 0.1, 1, 10, 100, 1000 (docs/results.md).
template <typename Cost>
struct AreaPreservingCost {
  Cost base;
  double weight;
  using Update_tag = typename Cost::Update_tag;
  template <typename VPM, typename GT>
  void initialize(const Mesh& m, const VPM& vpm, const GT& gt) const {
    base.initialize(m, vpm, gt);
  }
  template <typename Profile, typename V>
  void update_after_collapse(const Profile& p, const V& v) const {
    base.update_after_collapse(p, v);
  }
  template <typename Profile>
  boost::optional<typename Profile::FT> operator()(
      const Profile& profile, const boost::optional<typename Profile::Point>& placement) const {
    auto c = base(profile, placement);
    if (!c || !placement) return c;
    const auto& vpm = profile.vertex_point_map();
    auto area = [](const K::Point_3& a, const K::Point_3& b, const K::Point_3& d) {
      return std::sqrt(CGAL::squared_area(a, b, d));
    };
    double before = 0, after = 0;
    int i = 0;
    // The first triangles are the edge's own faces, which the collapse removes.
    const int own = (profile.left_face_exists() ? 1 : 0) + (profile.right_face_exists() ? 1 : 0);
    for (const auto& t : profile.triangles()) {
      const K::Point_3& p = get(vpm, t.v0);
      const K::Point_3& q = get(vpm, t.v1);
      const K::Point_3& r = get(vpm, t.v2);
      before += area(p, q, r);
      if (i++ >= own) after += area(p, *placement, r);
    }
    const double d = after - before;
    return *c + weight * d * d;
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

// Rejects a collapse after which a triangle of the star would not be strictly
// counter-clockwise seen from above (a fold, or a sliver flat in x, y), and one that would
// move a border vertex (both ends on the border, joined by an interior edge).
struct NoFoldFilter {
  const Mesh* mesh;
  std::size_t* rejected;
  Outline outline;
  const std::function<bool(const double*, const double*, const double*)>* triangle_ok;
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(
      const Profile& profile, boost::optional<typename Profile::Point> placement) const {
    if (!placement) return placement;
    if (outline == Outline::kLocked && mesh->is_border(profile.v0(), false) &&
        mesh->is_border(profile.v1(), false)) {
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
      if (*triangle_ok) {
        const double a[3] = {p.x(), p.y(), p.z()}, b[3] = {q.x(), q.y(), q.z()},
                     c[3] = {r.x(), r.y(), r.z()};
        if (!(*triangle_ok)(a, b, c)) {
          ++*rejected;
          return boost::none;
        }
      }
    }
    return placement;
  }
};

}  // namespace

TriMesh qslim(const TriMesh& in, std::size_t keep, QslimStats* stats, const QslimOptions& options) {
  const Outline outline = options.outline;
  Mesh mesh;
  std::vector<VertexIndex> vi;
  vi.reserve(in.vertex_count());
  for (std::size_t v = 0; v < in.vertex_count(); ++v) {
    vi.push_back(mesh.add_vertex(K::Point_3(in.xyz[3 * v], in.xyz[3 * v + 1], in.xyz[3 * v + 2])));
  }
  for (const auto& f : in.faces) {
    if (mesh.add_face(vi[f[0]], vi[f[1]], vi[f[2]]) == Mesh::null_face()) {
      throw std::invalid_argument("qslim: the mesh is not a manifold surface");
    }
  }
  QslimStats local;
  QslimStats& st = stats ? *stats : local;
  st.input_vertices = mesh.number_of_vertices();
  const NoFoldFilter filter{&mesh, &st.rejected_folds, outline, &options.triangle_ok};
  if (outline == Outline::kLocked) {
    // The paper's competitor: classic plane quadrics (Garland and Heckbert 1997), CGAL's
    // default weight on the outline's quadrics.
    using Policies = SMS::GarlandHeckbert_plane_policies<Mesh, K>;
    Policies policies(mesh);
    const BorderMap border{&mesh};
    const SMS::Constrained_placement<Policies::Get_placement, BorderMap> placement(
        border, policies.get_placement());
    SMS::edge_collapse(mesh, VertexCountStop{&mesh, keep},
                       CGAL::parameters::get_cost(policies.get_cost())
                           .get_placement(placement)
                           .edge_is_constrained_map(border)
                           .filter(filter));
  } else {
    // Triangle quadrics (Trettner and Kobbelt, "Fast and robust QEF minimization using
    // probabilistic quadrics", Eurographics 2020: the squared distance to each whole triangle,
    // so weighted by its size) and the outline's quadrics at weight 1: the outline cannot move
    // anyway. On st_helens_crater, 60 points x 3 sets, error x1e-4 at 10/30/50/70 %: plane
    // quadrics, weight 100: 18.5/5.68/2.72/1.21; triangle, 100: 18.3/5.75/2.56/1.09;
    // triangle, 1: 17.5/5.74/2.57/1.08 (probabilistic triangle quadrics: 66.8 at 10 %).
    using Policies = SMS::GarlandHeckbert_triangle_policies<Mesh, K>;
    Policies policies(mesh, 1.0);
    // Pinched vertices: more than one border halfedge into them (more than two outline edges).
    std::vector<char> border_in(in.vertex_count(), 0), pinched(in.vertex_count(), 0);
    for (Mesh::Halfedge_index h : mesh.halfedges()) {
      if (!mesh.is_border(h)) continue;
      const std::size_t v = mesh.target(h).idx();
      if (border_in[v]) pinched[v] = 1;
      border_in[v] = 1;
    }
    const OutlinePlacement<Policies::Get_placement, Policies::Get_cost> placement{
        policies.get_placement(), policies.get_cost(), &mesh, &options.outline_chord_ok, &pinched};
    SMS::edge_collapse(mesh, VertexCountStop{&mesh, keep},
                       CGAL::parameters::get_cost(
                           AreaPreservingCost<Policies::Get_cost>{policies.get_cost(), 100.0})
                           .get_placement(placement)
                           .filter(filter));
  }
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

// Exact geodesics with CGAL's Surface_mesh_shortest_path: S.-Q. Xin and G.-J. Wang, "Improving
// Chen and Han's algorithm on the discrete geodesic problem", ACM TOG 28(4), 2009.
#include "core/exact_geodesic.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_shortest_path.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace dpts::core {
namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<Kernel::Point_3>;
using Traits = CGAL::Surface_mesh_shortest_path_traits<Kernel, Mesh>;
using ShortestPath = CGAL::Surface_mesh_shortest_path<Traits>;

double cross_xy(double ux, double uy, double vx, double vy) { return ux * vy - uy * vx; }
}  // namespace

struct ExactGeodesics::Impl {
  Mesh mesh;
};

ExactGeodesics::ExactGeodesics(const TriMesh& tin) : impl_(std::make_unique<Impl>()) {
  Mesh& mesh = impl_->mesh;
  // Vertices as faces first use them: CGAL's propagation expects no isolated vertex.
  std::vector<Mesh::Vertex_index> vertex(tin.vertex_count(), Mesh::null_vertex());
  std::vector<std::uint32_t> uses(tin.vertex_count(), 0);
  for (std::size_t f = 0; f < tin.faces.size(); ++f) {
    Mesh::Vertex_index v[3];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = tin.faces[f][k];
      if (vertex[i] == Mesh::null_vertex()) {
        vertex[i] = mesh.add_vertex(Kernel::Point_3(tin.xyz[3 * i], tin.xyz[3 * i + 1],
                                                    tin.xyz[3 * i + 2]));
      }
      v[k] = vertex[i];
      ++uses[i];
    }
    // note: faces are added in order and none is removed, so face f is CGAL's Face_index(f).
    if (mesh.add_face(v[0], v[1], v[2]) == Mesh::null_face()) {
      throw std::invalid_argument(
          "face " + std::to_string(f) +
          " cannot join the surface for exact geodesics (an edge of a third face, an edge "
          "shared in the same direction as a neighbour's: a folded face, or a vertex joining "
          "separate fans)");
    }
  }
  // A vertex where separate fans of faces meet (CGAL links them through border halfedges) is
  // not a surface point the propagation can unfold: refuse it rather than measure paths that
  // avoid or misread it. note: a manifold vertex has at most one border around it.
  for (std::size_t i = 0; i < tin.vertex_count(); ++i) {
    if (uses[i] == 0) continue;
    std::uint32_t faces = 0, borders = 0;
    for (const auto f : CGAL::faces_around_target(mesh.halfedge(vertex[i]), mesh)) {
      (f == Mesh::null_face() ? borders : faces) += 1;
    }
    if (faces != uses[i] || borders > 1) {
      throw std::invalid_argument("vertex " + std::to_string(i) + " joins " +
                                  std::to_string(uses[i]) +
                                  " faces that do not form one fan (a non-manifold vertex): "
                                  "exact geodesics cannot pass it");
    }
  }
}

ExactGeodesics::~ExactGeodesics() = default;

std::size_t ExactGeodesics::face_count() const { return impl_->mesh.number_of_faces(); }

std::vector<double> ExactGeodesics::distances(const SurfacePoint& source,
                                              const std::vector<SurfacePoint>& targets) const {
  const Mesh& mesh = impl_->mesh;
  // A point's location: its face and barycentric coordinates in CGAL's vertex order of the
  // face (source, target of halfedge(f), then the next target).
  auto locate = [&](const SurfacePoint& p) {
    if (p.face >= mesh.number_of_faces()) {
      throw std::invalid_argument("exact geodesics: a point's face " + std::to_string(p.face) +
                                  " is not a face of the mesh");
    }
    const Mesh::Face_index f(p.face);
    const auto h = mesh.halfedge(f);
    const Kernel::Point_3& w0 = mesh.point(mesh.source(h));
    const Kernel::Point_3& w1 = mesh.point(mesh.target(h));
    const Kernel::Point_3& w2 = mesh.point(mesh.target(mesh.next(h)));
    // note: relative to w0, so that UTM-sized coordinates cost no precision.
    const double bx = w1.x() - w0.x(), by = w1.y() - w0.y(), bz = w1.z() - w0.z();
    const double cx = w2.x() - w0.x(), cy = w2.y() - w0.y(), cz = w2.z() - w0.z();
    const double qx = p.x - w0.x(), qy = p.y - w0.y(), qz = p.z - w0.z();
    double l1 = 0, l2 = 0;
    const double area = cross_xy(bx, by, cx, cy);
    const double scale = std::hypot(bx, by) * std::hypot(cx, cy);
    if (std::fabs(area) > 1e-12 * scale) {
      l1 = cross_xy(qx, qy, cx, cy) / area;
      l2 = cross_xy(bx, by, qx, qy) / area;
    } else {
      // A face vertical in x, y: its points are told apart by z (least squares in 3D).
      const double bb = bx * bx + by * by + bz * bz, bc = bx * cx + by * cy + bz * cz;
      const double cc = cx * cx + cy * cy + cz * cz;
      const double qb = qx * bx + qy * by + qz * bz, qc = qx * cx + qy * cy + qz * cz;
      const double det = bb * cc - bc * bc;
      if (det > 0) {
        l1 = (cc * qb - bc * qc) / det;
        l2 = (bb * qc - bc * qb) / det;
      }
    }
    // Points on an edge come out a rounding error outside it: clamp onto the face.
    double l[3] = {std::max(0.0, 1.0 - l1 - l2), std::max(0.0, l1), std::max(0.0, l2)};
    const double sum = l[0] + l[1] + l[2];
    for (double& x : l) x /= sum;
    return ShortestPath::Face_location(f, {{l[0], l[1], l[2]}});
  };
  ShortestPath sp(mesh);
  sp.add_source_point(locate(source));
  std::vector<double> out;
  out.reserve(targets.size());
  for (const SurfacePoint& t : targets) {
    const auto loc = locate(t);
    const double d = sp.shortest_distance_to_source_points(loc.first, loc.second).first;
    // note: CGAL answers a negative distance where no propagation reached the face.
    out.push_back(d >= 0 ? d : std::numeric_limits<double>::infinity());
  }
  return out;
}

}  // namespace dpts::core

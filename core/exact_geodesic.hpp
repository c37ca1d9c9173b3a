// Exact geodesic distances on a TIN with CGAL's Surface_mesh_shortest_path (Xin and Wang's
// improvement of the Chen-Han algorithm): the reference the Steiner-graph distances approximate.
#pragma once

#include <memory>
#include <vector>

#include "core/steiner_graph.hpp"

namespace dpts::core {

// A TIN as CGAL's shortest-path algorithm sees it, built once and queried from many sources.
// Cost per source (one full propagation whatever the targets): on a 100 x 100 grid TIN about
// 0.75 s and 250 MB (see README); meant for small meshes, as the reference of small tests.
class ExactGeodesics {
 public:
  // Copies the mesh into a CGAL Surface_mesh, face f becoming CGAL's face f. Throws
  // std::invalid_argument naming the face when one cannot join the surface: an edge it would
  // give a third face, an edge it shares in the same direction as its neighbour (faces
  // oriented against each other, e.g. a folded face), or a vertex whose faces would not form
  // fans. The mesh need not outlive this object.
  explicit ExactGeodesics(const TriMesh& mesh);
  ~ExactGeodesics();
  ExactGeodesics(const ExactGeodesics&) = delete;
  ExactGeodesics& operator=(const ExactGeodesics&) = delete;

  // Exact surface distances (metres) from source to each target; +infinity where a target
  // lies in another connected part of the mesh. Points are located by their face (faces of
  // the TriMesh given at construction) and their x, y in it (barycentric coordinates in x, y;
  // in 3D for a face that is vertical). const and free of shared state: threads may query
  // one object at once, each query holding its own propagation (its memory is freed on return).
  std::vector<double> distances(const SurfacePoint& source,
                                const std::vector<SurfacePoint>& targets) const;

  std::size_t face_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dpts::core

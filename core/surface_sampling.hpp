// The DEM's full-resolution grid TIN, uniform sample points on a TIN, and point location.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/grid.hpp"
#include "core/mesh.hpp"
#include "core/steiner_graph.hpp"

namespace dpts::core {

// Which diagonal splits each full grid square.
enum class Diagonal { nw_se, ne_sw };

// The diagonal the Delaunay triangulation of the grid in `frame` takes: NW-SE
// (row,col)-(row+1,col+1) for a square or rectangular grid (a tie, broken so by CGAL's
// symbolic perturbation), the shorter one for a sheared grid (a reprojected DEM).
Diagonal delaunay_diagonal(const GridFrame& frame);

// The full-resolution TIN T of a DEM: every grid square with 4 valid corners split along the
// given diagonal, every square with exactly 3 valid corners as that triangle (the valid
// footprint, see footprint.hpp). With delaunay_diagonal(frame) this is the Delaunay TIN the
// elimination starts from. Vertices are the surface cells (ascending); faces index them, in
// the grid's orientation (fix_orientation() makes them counter-clockwise in a given CRS).
// With opposites given: per half-edge (face f's k-th runs from corner k to corner k + 1 mod 3,
// numbered 3 f + k) the other face's half-edge on the same edge, or kNoOpposite on the
// outline: known from the squares, where a mesh's own pairing searches (qem's input).
constexpr std::uint32_t kNoOpposite = 0xFFFFFFFFu;
Tin grid_tin(const HeightGrid& grid, Diagonal diagonal = Diagonal::nw_se,
             std::vector<std::uint32_t>* opposites = nullptr);

// Reverses every face that is clockwise in mesh.xyz's x, y; with opposites given (grid_tin's
// for these faces), renumbers them for the reversed faces.
void fix_orientation(TriMesh& mesh, std::vector<std::uint32_t>* opposites = nullptr);

// The grid TIN (grid_tin with delaunay_diagonal(frame)) in the frame: vertices (u, w, height in
// frame units) of its cells, faces counter-clockwise. In the frame collinear cells stay exactly
// collinear, so a fold test sees flat slivers along the outline of a reprojected DEM as flat
// (QSlim works here). No faces when no three neighbouring cells are valid.
TriMesh frame_grid_mesh(const HeightGrid& grid, const GridFrame& frame);

// `count` points uniform in the area of the mesh (in x, y), seeded; z lifted onto the mesh.
std::vector<SurfacePoint> sample_uniform(const TriMesh& mesh, std::size_t count,
                                         std::uint64_t seed);

// Locates points in a mesh's faces (in x, y) with a bucket grid.
class PointLocator {
 public:
  explicit PointLocator(const TriMesh& mesh);
  // The lowest-numbered face containing (x, y) (edges included, up to rounding), lifted; or,
  // when none does, the nearest face if (x, y) lies within `snap` of it, flagged as snapped.
  struct Hit {
    SurfacePoint point;
    bool snapped = false;
  };
  std::optional<Hit> locate(double x, double y, double snap = 0.0) const;

 private:
  const TriMesh& mesh_;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<std::uint32_t> first_, faces_;  // CSR bucket -> faces
};

}  // namespace dpts::core

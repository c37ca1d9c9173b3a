// Structural checks of a triangle mesh seen from above.
#include "core/mesh_check.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace dpts::core {

namespace {
double twice_area(const std::vector<double>& xy, const std::array<std::uint32_t, 3>& f) {
  const double ax = xy[2 * f[0]], ay = xy[2 * f[0] + 1];
  return (xy[2 * f[1]] - ax) * (xy[2 * f[2] + 1] - ay) -
         (xy[2 * f[1] + 1] - ay) * (xy[2 * f[2]] - ax);
}
}  // namespace

double mesh_area(const std::vector<double>& xy,
                 const std::vector<std::array<std::uint32_t, 3>>& faces) {
  double area = 0.0;
  for (const auto& f : faces) area += 0.5 * twice_area(xy, f);
  return area;
}

std::vector<double> xy_of(const std::vector<double>& xyz) {
  std::vector<double> xy(2 * (xyz.size() / 3));
  for (std::size_t v = 0; v < xyz.size() / 3; ++v)
    xy[2 * v] = xyz[3 * v], xy[2 * v + 1] = xyz[3 * v + 1];
  return xy;
}

MeshCheck check_mesh(const std::vector<double>& xy,
                     const std::vector<std::array<std::uint32_t, 3>>& faces) {
  MeshCheck result;
  result.faces = faces.size();
  std::vector<std::pair<std::uint64_t, int>> edges;  // (min,max) key, +1 forward / -1 backward
  edges.reserve(faces.size() * 3);
  for (const auto& f : faces) {
    const double area2 = twice_area(xy, f);
    if (!(area2 > 0)) ++result.clockwise_or_flat;
    result.area += 0.5 * area2;
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t p = f[i], q = f[(i + 1) % 3];
      const std::uint64_t key = (std::uint64_t{std::min(p, q)} << 32) | std::max(p, q);
      edges.emplace_back(key, p < q ? 1 : -1);
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    int sum = 0;
    while (j < edges.size() && edges[j].first == edges[i].first) sum += edges[j++].second;
    const std::size_t uses = j - i;
    if (uses == 1) {
      ++result.boundary_edges;
      const std::uint64_t p = edges[i].first >> 32, q = edges[i].first & 0xFFFFFFFFu;
      result.boundary_length += std::hypot(xy[2 * q] - xy[2 * p], xy[2 * q + 1] - xy[2 * p + 1]);
    } else if (uses > 2 || sum != 0) {
      ++result.bad_edges;
    }
    i = j;
  }
  return result;
}

std::size_t faces_over_nodata(const HeightGrid& grid, const std::vector<double>& grid_xy,
                              const std::vector<std::array<std::uint32_t, 3>>& faces,
                              double tolerance) {
  std::size_t bad = 0;
  for (const auto& f : faces) {
    double x[3], y[3];
    for (int i = 0; i < 3; ++i) x[i] = grid_xy[2 * f[i]], y[i] = grid_xy[2 * f[i] + 1];
    const double area2 = (x[1] - x[0]) * (y[2] - y[0]) - (y[1] - y[0]) * (x[2] - x[0]);
    const double sign = area2 >= 0 ? 1.0 : -1.0;
    const int c0 = static_cast<int>(std::floor(std::min({x[0], x[1], x[2]}) - tolerance));
    const int c1 = static_cast<int>(std::ceil(std::max({x[0], x[1], x[2]}) + tolerance));
    const int r0 = static_cast<int>(std::floor(std::min({y[0], y[1], y[2]}) - tolerance));
    const int r1 = static_cast<int>(std::ceil(std::max({y[0], y[1], y[2]}) + tolerance));
    bool over = c0 < -1 || r0 < -1 || c1 > grid.width || r1 > grid.height;
    for (int r = std::max(r0, 0); r <= std::min(r1, grid.height - 1) && !over; ++r) {
      for (int c = std::max(c0, 0); c <= std::min(c1, grid.width - 1) && !over; ++c) {
        if (grid.is_valid(c, r)) continue;
        // Inside or on the triangle (edges widened by the tolerance)?
        bool inside = true;
        for (int i = 0; i < 3 && inside; ++i) {
          const int j = (i + 1) % 3;
          const double ex = x[j] - x[i], ey = y[j] - y[i];
          const double len = std::hypot(ex, ey);
          const double side = sign * (ex * (r - y[i]) - ey * (c - x[i])) / (len > 0 ? len : 1.0);
          inside = side >= -tolerance;
        }
        over = inside;
      }
    }
    if (over) ++bad;
  }
  return bad;
}

std::size_t weld_identical_vertices(TriMesh& mesh) {
  const std::size_t n = mesh.vertex_count();
  auto at = [&](std::uint32_t v) {
    return std::array<double, 3>{mesh.xyz[3 * v], mesh.xyz[3 * v + 1], mesh.xyz[3 * v + 2]};
  };
  // Sort by position, then index: each run of equal positions starts with its first vertex.
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t v = 0; v < n; ++v) order[v] = v;
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const auto pa = at(a), pb = at(b);
    return pa != pb ? pa < pb : a < b;
  });
  std::vector<std::uint32_t> first(n);
  for (std::size_t k = 0; k < n; ++k) {
    first[order[k]] = k > 0 && at(order[k]) == at(order[k - 1]) ? first[order[k - 1]] : order[k];
  }
  // Keep the first of each position, in index order; the others take its new index.
  std::vector<std::uint32_t> index(n);
  std::vector<double> xyz;
  xyz.reserve(mesh.xyz.size());
  std::uint32_t kept = 0;
  for (std::uint32_t v = 0; v < n; ++v) {
    if (first[v] == v) {
      index[v] = kept++;
      xyz.insert(xyz.end(), mesh.xyz.begin() + 3 * v, mesh.xyz.begin() + 3 * v + 3);
    } else {
      index[v] = index[first[v]];  // note: first[v] < v, so its index is already set
    }
  }
  if (kept == n) return 0;
  for (auto& f : mesh.faces) {
    for (auto& v : f) v = index[v];
  }
  mesh.xyz = std::move(xyz);
  return n - kept;
}

}  // namespace dpts::core

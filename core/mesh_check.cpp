// Structural checks of a triangle mesh seen from above.
#include "core/mesh_check.hpp"

#include <algorithm>
#include <utility>

namespace dpts::core {

MeshCheck check_mesh(const std::vector<double>& xy,
                     const std::vector<std::array<std::uint32_t, 3>>& faces) {
  MeshCheck result;
  result.faces = faces.size();
  std::vector<std::pair<std::uint64_t, int>> edges;  // (min,max) key, +1 forward / -1 backward
  edges.reserve(faces.size() * 3);
  for (const auto& f : faces) {
    const double ax = xy[2 * f[0]], ay = xy[2 * f[0] + 1];
    const double bx = xy[2 * f[1]], by = xy[2 * f[1] + 1];
    const double cx = xy[2 * f[2]], cy = xy[2 * f[2] + 1];
    const double area2 = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
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
    } else if (uses > 2 || sum != 0) {
      ++result.bad_edges;
    }
    i = j;
  }
  return result;
}

}  // namespace dpts::core

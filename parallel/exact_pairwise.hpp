// Exact geodesic distances between all pairs of sample points (CGAL's Surface_mesh_shortest_path
// per source), spread over oneTBB tasks: the reference mode of dpts-eval (--exact).
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "core/exact_geodesic.hpp"

namespace dpts::par {

// Exact distances between all pairs of points on the mesh of `geodesics`: out[i * K + j] for
// i < j (the rest 0), +infinity where j lies in another connected part than i. One exact
// propagation per source i < K - 1 (targets j > i), one task each; each result has its own
// slot, so the figures are the same for any thread count. Memory: one propagation per thread
// at once, not bounded (about 250 MB on a 100 x 100 grid TIN, see README). on_source, if
// given, is called as each source is done with the number done so far (1 to K - 1), serialized,
// from any worker thread; answering false stops the run: no other source starts, and once those
// under way are done, dpts::Cancelled is thrown. Exceptions of a task (std::invalid_argument
// for a point whose face is not the mesh's) come out in the caller.
std::vector<double> exact_pairwise_distances(
    const core::ExactGeodesics& geodesics, const std::vector<core::SurfacePoint>& points,
    const std::function<bool(std::size_t done)>& on_source = nullptr);

}  // namespace dpts::par

// The Steiner-graph distances checked against exact geodesics (core::ExactGeodesics: CGAL's
// Surface_mesh_shortest_path), on hand-made TINs and crops of real DEMs.
#pragma once

#include <string>
#include <vector>

#include "core/steiner_graph.hpp"

namespace dpts::test {

// Exact distances from source to each target on mesh (points on the mesh, their face set):
// core::ExactGeodesics built for this one source.
std::vector<double> exact_geodesics(const core::TriMesh& mesh, const core::SurfacePoint& source,
                                    const std::vector<core::SurfacePoint>& targets);

// A size x size crop (from column c0, row r0) of a DEM's band 1 as a grid TIN in metres (the
// DEM's metric frame). Throws if the crop has no-data.
core::TriMesh dem_crop(const std::string& path, int c0, int r0, int size);

struct AccuracyFigures {
  double mean_rel = 0, max_rel = 0, min_rel = 0;  // (Steiner - exact) / exact over all pairs
  std::size_t pairs = 0;
};

// Compares Steiner distances at spacing delta with exact ones for `sources` sources and
// `targets` targets sampled uniformly on the mesh (seeded).
AccuracyFigures steiner_accuracy(const core::TriMesh& mesh, double delta, int sources, int targets,
                                 std::uint64_t seed);

}  // namespace dpts::test

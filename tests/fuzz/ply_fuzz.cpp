// libFuzzer harness: the PLY reader and what dpts-eval does with a mesh it accepts
// (structural checks, point location, Steiner graph and geodesics against a fixed grid TIN).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "core/mesh_check.hpp"
#include "core/surface_sampling.hpp"
#include "io/ply.hpp"
#include "parallel/evaluate.hpp"

namespace {

// T: a 5 x 5 grid TIN on [0, 4]^2 (the DEM side of dpts-eval), faces counter-clockwise.
dpts::core::TriMesh grid_tin() {
  dpts::core::TriMesh t;
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 5; ++c) t.xyz.insert(t.xyz.end(), {double(c), double(r), 0.1 * c * r});
  }
  for (std::uint32_t r = 0; r < 4; ++r) {
    for (std::uint32_t c = 0; c < 4; ++c) {
      const std::uint32_t v = 5 * r + c;
      t.faces.push_back({v, v + 1, v + 6});
      t.faces.push_back({v, v + 6, v + 5});
    }
  }
  return t;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace dpts;
  static const core::TriMesh t = grid_tin();
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  io::Mesh ply;
  try {
    ply = io::read_ply(in, "fuzz.ply");
    io::check_triangles(ply, "fuzz.ply");
  } catch (const InputError&) {
    return 0;  // refused with a message: the expected answer to a malformed file
  }
  // dpts-eval refuses meshes outside the DEM's extent (1 % margin); small meshes keep the
  // harness at thousands of runs a second.
  for (std::size_t i = 0; i < ply.xyz.size(); i += 3) {
    if (ply.xyz[i] < -0.1 || ply.xyz[i] > 4.1 || ply.xyz[i + 1] < -0.1 || ply.xyz[i + 1] > 4.1 ||
        ply.xyz[i + 2] < -100 || ply.xyz[i + 2] > 100) {
      return 0;
    }
  }
  if (ply.vertex_count() > 64 || ply.faces.size() > 128) return 0;
  const core::TriMesh s{std::move(ply.xyz), std::move(ply.faces)};
  const std::vector<double> xy = core::xy_of(s.xyz);
  core::check_mesh(xy, s.faces);
  const core::PointLocator locate(s);
  for (std::size_t v = 0; v < s.vertex_count(); ++v) locate.locate(xy[2 * v], xy[2 * v + 1], 0.5);
  par::EvalOptions options;
  options.points = 4;
  options.sets = 1;
  options.snap_m = 0.5;
  try {
    par::evaluate_distances(t, s, options);
  } catch (const InputError&) {  // sample points off the mesh
  } catch (const std::invalid_argument&) {  // an edge of three faces
  }
  return 0;
}

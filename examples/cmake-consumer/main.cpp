// Simplifies a DEM with libdpts, writes the TIN, measures it, and shows a cancelled call.
#include <cstdio>
#include <dpts/dpts.hpp>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer DEM OUT.ply\n");
    return 2;
  }
  try {
    dpts::SimplifyOptions options;
    options.keep = 0.1;
    int calls = 0;
    const dpts::Mesh mesh = dpts::simplify(argv[1], options, [&](double, std::string_view) {
      ++calls;
      return true;
    });
    mesh.write(argv[2]);
    std::printf("dpts %s: %zu -> %zu vertices, %zu faces, %d progress calls\n",
                dpts::version().c_str(), mesh.input_vertices, mesh.vertex_count(),
                mesh.faces.size(), calls);
    dpts::EvaluateOptions eo;
    eo.points = 20;
    eo.sets = 1;
    const dpts::Evaluation e = dpts::evaluate(argv[1], argv[2], eo);
    std::printf("distance error %.6f, vertical RMSE %.3f m\n", e.distance_error, e.vertical_rmse);
    try {
      dpts::simplify(argv[1], options, [](double, std::string_view) { return false; });
    } catch (const dpts::Cancelled& c) {
      std::printf("a stopped call throws: %s\n", c.what());
    }
  } catch (const dpts::Error& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}

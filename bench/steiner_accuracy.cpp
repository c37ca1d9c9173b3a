// Prints the accuracy of Steiner-graph distances against CGAL's exact geodesics on 50 x 50
// crops of real DEMs, for several spacings delta (fractions of the mean edge length).
// Usage: steiner_accuracy [SOURCES TARGETS]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "parallel/evaluate.hpp"
#include "support/exact_geodesic.hpp"

int main(int argc, char** argv) {
  const int sources = argc > 1 ? std::atoi(argv[1]) : 10;
  const int targets = argc > 2 ? std::atoi(argv[2]) : 30;
  const std::string data = DPTS_SHARED_DATA_DIR;
  struct Crop {
    const char* file;
    int c0, r0;
  };
  const Crop crops[] = {{"st_helens_crater.tif", 39, 39},
                        {"san_gabriel_bigtujunga_utm11.tif", 600, 300}};
  std::printf("crop,delta_factor,delta_m,pairs,mean_rel_diff,max_rel_diff,min_rel_diff\n");
  for (const Crop& c : crops) {
    const auto mesh = dpts::test::dem_crop(data + "/" + c.file, c.c0, c.r0, 50);
    const double mean_edge = dpts::core::mean_edge_length(mesh);
    for (double f : {1.0, 0.5, 0.33, 0.25}) {
      const auto fig = dpts::test::steiner_accuracy(mesh, f * mean_edge, sources, targets, 7);
      std::printf("%s[%d:%d],%.2f,%.3f,%zu,%.5f,%.5f,%.5f\n", c.file, c.c0, c.r0, f, f * mean_edge,
                  fig.pairs, fig.mean_rel, fig.max_rel, fig.min_rel);
      std::fflush(stdout);
    }
  }
  std::printf("# default delta factor: %.2f\n", dpts::par::kDefaultDeltaFactor);
}

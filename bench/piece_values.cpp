// Piece values (the DPTS paper's CalcPieceValue: mean ED/GD of l random point pairs) computed
// on subsampled grids against full resolution, on the 4 x 4 pieces of a real DEM: the evidence
// for dpts-par's cheaper default (at most 4096 cells per piece value). Prints one line per
// piece and, per grid size, the mean and max |difference| and Spearman's rank correlation.
// Usage: build/bench/piece_values [DEM] (default: the shared San Gabriel DEM)
#include <gdal_priv.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include "io/dem_reader.hpp"
#include "parallel/meta.hpp"

namespace {

std::vector<double> ranks(const std::vector<double>& v) {
  std::vector<std::size_t> order(v.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return v[a] < v[b]; });
  std::vector<double> r(v.size());
  for (std::size_t k = 0; k < order.size(); ++k) r[order[k]] = static_cast<double>(k);
  return r;
}

double spearman(const std::vector<double>& a, const std::vector<double>& b) {
  const auto ra = ranks(a), rb = ranks(b);
  double d2 = 0;
  for (std::size_t i = 0; i < a.size(); ++i) d2 += (ra[i] - rb[i]) * (ra[i] - rb[i]);
  const double n = static_cast<double>(a.size());
  return 1.0 - 6.0 * d2 / (n * (n * n - 1.0));
}

}  // namespace

int main(int argc, char** argv) {
  using namespace dpts;
  GDALAllRegister();
  const std::string path =
      argc > 1 ? argv[1] : std::string(DPTS_SHARED_DATA_DIR) + "/san_gabriel_bigtujunga_utm11.tif";
  try {
    const io::DemInfo info = io::open_dem(path, {});
    io::WindowReader reader(info);
    const int n = 4, pw = info.width / n, ph = info.height / n;
    const std::vector<int> sizes = {1024, 4096, 16384, 1 << 30};
    std::vector<std::vector<double>> values(sizes.size());
    std::vector<double> seconds(sizes.size(), 0.0);
    std::printf("piece (%d x %d cells)", pw, ph);
    for (int s : sizes) std::printf("  %s", s == (1 << 30) ? "full" : std::to_string(s).c_str());
    std::printf("\n");
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const auto g = reader.read(i * pw, j * ph, pw, ph);
        std::printf("%d,%d", i, j);
        for (std::size_t k = 0; k < sizes.size(); ++k) {
          const auto t0 = std::chrono::steady_clock::now();
          const double v = par::piece_value(g, i * pw, j * ph, info.frame, 20, sizes[k],
                                            static_cast<std::uint64_t>(7 + i + n * j));
          seconds[k] +=
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          values[k].push_back(v);
          std::printf("  %.5f", v);
        }
        std::printf("\n");
        std::fflush(stdout);
      }
    }
    const auto& full = values.back();
    for (std::size_t k = 0; k + 1 < sizes.size(); ++k) {
      double sum = 0, worst = 0;
      for (std::size_t p = 0; p < full.size(); ++p) {
        const double d = std::fabs(values[k][p] - full[p]);
        sum += d;
        worst = std::max(worst, d);
      }
      std::printf(
          "# <= %5d cells: mean |diff| %.4f, max %.4f, Spearman %.3f, %.2f s per piece "
          "(full: %.2f s)\n",
          sizes[k], sum / full.size(), worst, spearman(values[k], full), seconds[k] / full.size(),
          seconds.back() / full.size());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "piece_values: %s\n", e.what());
    return 1;
  }
  return 0;
}

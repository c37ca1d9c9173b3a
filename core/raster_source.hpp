// A raster DEM as the piece engines see it: its size and planar frame, window reads of one band
// of heights with its no-data, and the map of its grid to the output CRS. The engines
// (parallel/) know nothing else of where it comes from: io/ implements it for any raster GDAL
// reads (io::GdalRaster), and MemoryRaster below holds a grid in memory (tests, benchmarks).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/grid.hpp"
#include "core/steiner_graph.hpp"

namespace dpts::core {

// Values rasters commonly store for no-data (ESRI's -9999, SRTM's -32768, the 16-bit types'
// extremes, ...), as stored (before a band's scale and offset). Cells holding them in a band
// without a no-data value (or with another) are most likely voids that lost their tag: they read
// as pits or towers kilometres deep or high, which no height check can tell from terrain, so
// they are counted and said.
inline constexpr std::array<double, 6> kUsualNoData = {-9999.0, -32768.0, -32767.0,
                                                         -99999.0, 32767.0, 65535.0};
using UsualNoDataCounts = std::array<std::size_t, kUsualNoData.size()>;

// One object per input, shared by every task of a run: all members are safe to call from
// concurrent tasks.
class RasterSource {
 public:
  virtual ~RasterSource() = default;

  // The input, as messages name it (a file's path).
  const std::string& name() const { return name_; }
  int width() const { return width_; }
  int height() const { return height_; }
  std::size_t cell_count() const { return static_cast<std::size_t>(width_) * height_; }
  // The metric frame of the grid (see core/grid.hpp).
  const GridFrame& frame() const { return frame_; }
  // Rows the source reads at once (a GDAL band's block height): strips of whole multiples of
  // it cost no block twice.
  int block_height() const { return block_height_; }

  // Cells read as no-data because their height was implausible (see io::kMaxAbsHeight),
  // counted for rows [row0, row1) only (a streaming pass's overlapping strips count once).
  // Also the cells holding each of kUsualNoData other than the band's no-data value (read as
  // heights, as the band says).
  struct Implausible {
    int row0 = 0, row1 = std::numeric_limits<int>::max();
    std::size_t cells = 0;
    UsualNoDataCounts usual{};
  };
  // Heights of columns [col0, col0 + width) and rows [row0, row0 + height), inside the raster;
  // NaN for no-data (the band's value, its mask, NaN, infinite and implausible heights).
  // Adds the implausible cells to *implausible if given. Throws InputError naming the input
  // when the read fails.
  virtual HeightGrid read(int col0, int row0, int width, int height,
                          Implausible* implausible = nullptr) const = 0;
  // True when the window is known to hold no valid cell without reading it (a sparse file's
  // unwritten blocks); false when in doubt.
  virtual bool empty(int /*col0*/, int /*row0*/, int /*width*/, int /*height*/) const {
    return false;
  }
  // The message for a raster without a valid cell, naming the input; absurd_cells: cells
  // whose heights were read as no-data for their size (beyond +-1e7).
  virtual std::string no_valid_cell_message(std::size_t absurd_cells) const {
    return name_ + ": has no valid cell" +
           (absurd_cells > 0 ? " (" + std::to_string(absurd_cells) +
                                   " with heights beyond +-1e7, read as no-data)"
                             : std::string());
  }

  // The output CRS. reprojected: the cells' positions there are not linear in the frame (a
  // geographic DEM projected to UTM), so the engines place vertices by output_xy_of_grid.
  virtual bool reprojected() const = 0;
  // Grid positions (col, row pairs; cell centres at integers) in the output CRS: x0, y0, ...
  virtual std::vector<double> output_xy_of_grid(const std::vector<double>& grid_xy) const = 0;
  virtual double metres_per_output_unit() const = 0;
  // The inverse map, output CRS to (col, row); false where it fails. One per task.
  virtual std::function<bool(double x, double y, double& col, double& row)> grid_of_output_fn()
      const = 0;
  // For a reprojected source: the test of core's outline rule for cells of a window
  // `window_width` wide (0: the raster's width) whose first cell is (col0, row0), cells given
  // as window-local row-major indices (see io::DemInfo::outline_chord_test). Null when the
  // frame is exact.
  virtual std::function<bool(std::uint64_t, std::uint64_t)> outline_chord_test(
      int col0 = 0, int row0 = 0, int window_width = 0) const = 0;
  // A mesh in the frame (u, w, heights in frame units) moved to the output CRS in place.
  virtual void frame_mesh_to_output(TriMesh& mesh) const = 0;

 protected:
  RasterSource(std::string name, int width, int height, const GridFrame& frame,
               int block_height = 1)
      : name_(std::move(name)),
        width_(width),
        height_(height),
        frame_(frame),
        block_height_(block_height > 0 ? block_height : 1) {}

 private:
  std::string name_;
  int width_, height_;
  GridFrame frame_;
  int block_height_;
};

// A grid in memory as a source: output coordinates are the frame's in metres (x = u, y = w
// times metres_per_unit), nothing is reprojected.
class MemoryRaster final : public RasterSource {
 public:
  // Throws std::invalid_argument when the grid's size does not match its heights.
  MemoryRaster(HeightGrid grid, const GridFrame& frame, std::string name = "memory");
  HeightGrid read(int col0, int row0, int width, int height,
                  Implausible* implausible = nullptr) const override;
  bool reprojected() const override { return false; }
  std::vector<double> output_xy_of_grid(const std::vector<double>& grid_xy) const override;
  double metres_per_output_unit() const override { return 1.0; }
  std::function<bool(double, double, double&, double&)> grid_of_output_fn() const override;
  std::function<bool(std::uint64_t, std::uint64_t)> outline_chord_test(int, int,
                                                                       int) const override {
    return nullptr;
  }
  void frame_mesh_to_output(TriMesh& mesh) const override;

 private:
  HeightGrid grid_;
};

}  // namespace dpts::core

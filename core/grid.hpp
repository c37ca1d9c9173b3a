// In-memory height grid and the planar frame the core works in.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace dpts::core {

// Most cells a HeightGrid may have: core's cell indices are 32-bit.
inline constexpr std::size_t kMaxGridCells = 0xFFFFFFFFu;

// Heights of a DEM band, row-major (row 0 first), metres. NaN marks no-data.
// Cell (col, row) has index row * width + col; indices fit in 32 bits (kMaxGridCells).
struct HeightGrid {
  int width = 0;
  int height = 0;
  std::vector<double> z;

  bool is_valid(int col, int row) const {
    return col >= 0 && row >= 0 && col < width && row < height && !std::isnan(z[index(col, row)]);
  }
  std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(col);
  }
  std::size_t cell_count() const { return z.size(); }
};

// Linear map from grid (col, row) to the planar frame (u, w) the triangulation uses:
//   u = m[0][0] * col + m[0][1] * row,   w = m[1][0] * col + m[1][1] * row,
// and metres = metres_per_unit * (u, w). The entries are multiples of 2^-24 so that the map
// is exact in double arithmetic for grids up to 2^24 cells a side: cells collinear in the
// grid stay exactly collinear in the frame (the footprint outline stays straight), and a
// square north-up grid maps to integers (exact, fast Delaunay predicates).
// The frame has the orientation of the output CRS (x east, y north), so counter-clockwise
// in the frame is counter-clockwise in the output.
struct GridFrame {
  double m[2][2] = {{1.0, 0.0}, {0.0, -1.0}};
  double metres_per_unit = 1.0;

  double u(int col, int row) const { return m[0][0] * col + m[0][1] * row; }
  double w(int col, int row) const { return m[1][0] * col + m[1][1] * row; }
  // A cell's sides in metres: one column step, one row step.
  double col_metres() const { return metres_per_unit * std::hypot(m[0][0], m[1][0]); }
  double row_metres() const { return metres_per_unit * std::hypot(m[0][1], m[1][1]); }

  // The inverse map, frame (u, w) -> grid (col, row): col = inv[0] . (u, w), row = inv[1] . (u, w).
  void inverse(double inv[2][2]) const {
    const double det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    inv[0][0] = m[1][1] / det, inv[0][1] = -m[0][1] / det;
    inv[1][0] = -m[1][0] / det, inv[1][1] = m[0][0] / det;
  }

  // Frame for a metric Jacobian j (metres per column step and per row step:
  // j[0] = (dx/dcol, dx/drow), j[1] = (dy/dcol, dy/drow)). Throws std::invalid_argument
  // when the Jacobian is singular or not finite, or its cells are too thin (one side over
  // 10^4 times the other, or sides nearly parallel).
  static GridFrame from_jacobian(const double j[2][2]);
};

}  // namespace dpts::core

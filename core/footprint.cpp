// The valid footprint of a DEM (see footprint.hpp) and exact point-in-footprint tests.
#include "core/footprint.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace dpts::core {
namespace {

// Valid corners of square (c, r) as a bit set: 1 = (c,r), 2 = (c+1,r), 4 = (c,r+1),
// 8 = (c+1,r+1).
int square_mask(const HeightGrid& g, int c, int r) {
  return (g.is_valid(c, r) ? 1 : 0) | (g.is_valid(c + 1, r) ? 2 : 0) |
         (g.is_valid(c, r + 1) ? 4 : 0) | (g.is_valid(c + 1, r + 1) ? 8 : 0);
}

int popcount4(int m) { return (m & 1) + ((m >> 1) & 1) + ((m >> 2) & 1) + ((m >> 3) & 1); }

std::int64_t floor_div3(std::int64_t s) { return s >= 0 ? s / 3 : -((-s + 2) / 3); }

}  // namespace

GridFrame GridFrame::from_jacobian(const double j[2][2]) {
  const double det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
  if (!std::isfinite(det) || det == 0.0) {
    throw std::invalid_argument("singular or non-finite cell geometry");
  }
  // note: scale by the length of a column step so a square grid maps to unit cells, then
  // round every entry to a multiple of 2^-24 (exact products, see grid.hpp).
  const double scale = std::hypot(j[0][0], j[1][0]);
  GridFrame f;
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      f.m[a][b] = std::ldexp(std::nearbyint(std::ldexp(j[a][b] / scale, 24)), -24);
    }
  }
  // Cells with one side over 10^4 times the other (or nearly parallel sides) are no terrain
  // grid, and the rounding above would flatten them.
  const double det_rounded = f.m[0][0] * f.m[1][1] - f.m[0][1] * f.m[1][0];
  if (!(std::fabs(det_rounded) >= 1e-4) || !(std::fabs(det_rounded) <= 1e4)) {
    throw std::invalid_argument("cells are too thin: one side over 10^4 times the other");
  }
  f.metres_per_unit = scale;
  return f;
}

std::vector<std::uint32_t> surface_cells(const HeightGrid& grid) {
  // A cell is on the surface when a square with at least three valid corners uses it: each
  // square's corner mask computed once (a row of squares at a time), its valid corners marked.
  // note: where the per-cell test of its four squares took 16 validity tests a cell (2 % of
  // qem's instructions on San Gabriel, a grid read per piece).
  std::vector<std::uint32_t> cells;
  const int w = grid.width, h = grid.height;
  if (w < 2 || h < 2) return cells;
  std::vector<std::uint8_t> valid(static_cast<std::size_t>(w) * 2);  // rows r and r + 1
  std::vector<std::uint8_t> used(static_cast<std::size_t>(w) * 2);   // the same rows
  std::uint8_t* top_valid = valid.data();
  std::uint8_t* bottom_valid = valid.data() + w;
  std::uint8_t* top_used = used.data();
  std::uint8_t* bottom_used = used.data() + w;
  for (int c = 0; c < w; ++c) top_valid[c] = !std::isnan(grid.z[grid.index(c, 0)]);
  for (int r = 0; r < h; ++r) {
    // Squares (c, r) have their top corners on row r, their bottom ones on row r + 1.
    if (r + 1 < h) {
      for (int c = 0; c < w; ++c) bottom_valid[c] = !std::isnan(grid.z[grid.index(c, r + 1)]);
      for (int c = 0; c + 1 < w; ++c) {
        const int n = top_valid[c] + top_valid[c + 1] + bottom_valid[c] + bottom_valid[c + 1];
        if (n < 3) continue;
        top_used[c] |= top_valid[c];
        top_used[c + 1] |= top_valid[c + 1];
        bottom_used[c] |= bottom_valid[c];
        bottom_used[c + 1] |= bottom_valid[c + 1];
      }
    }
    for (int c = 0; c < w; ++c) {
      if (top_used[c]) cells.push_back(static_cast<std::uint32_t>(grid.index(c, r)));
    }
    std::swap(top_valid, bottom_valid);
    std::swap(top_used, bottom_used);
    std::fill(bottom_used, bottom_used + w, 0);
  }
  return cells;
}

namespace {

// Whether the pushed point with thirds (a, b) inside a square of the given corner mask lies
// in F (see footprint_contains_third).
bool square_contains(int mask, int a, int b) {
  switch (mask) {
    case 15:
      return true;
    case 14:
      return a + b >= 3;  // (c,r) missing: triangle of the other three, fx + fy > 1
    case 7:
      return a + b < 3;  // (c+1,r+1) missing: fx + fy < 1
    case 13:
      return b > a;  // (c+1,r) missing: fy > fx (eps^2 < eps on the diagonal)
    case 11:
      return a >= b;  // (c,r+1) missing: fx > fy
    default:
      return false;
  }
}

}  // namespace

bool footprint_contains_third(const HeightGrid& grid, std::int64_t sum_col, std::int64_t sum_row) {
  // note: with the push (+eps, +eps^2) a point on a grid line belongs to the square on its
  // right (below), so the square is simply the floor of the coordinates.
  const std::int64_t c = floor_div3(sum_col);
  const std::int64_t r = floor_div3(sum_row);
  if (c < 0 || r < 0 || c + 1 >= grid.width || r + 1 >= grid.height) return false;
  return square_contains(square_mask(grid, static_cast<int>(c), static_cast<int>(r)),
                         static_cast<int>(sum_col - 3 * c), static_cast<int>(sum_row - 3 * r));
}

FootprintIndex::FootprintIndex(const HeightGrid& grid)
    : width_(grid.width), height_(grid.height), mask_(grid.cell_count(), 0) {
  bool full = true;
  for (int r = 0; r + 1 < grid.height; ++r) {
    for (int c = 0; c + 1 < grid.width; ++c) {
      const int mask = square_mask(grid, c, r);
      mask_[grid.index(c, r)] = static_cast<std::uint8_t>(mask);
      full = full && mask == 15;
    }
  }
  // note: a DEM with every square whole (no no-data) needs no look-up: its masks are freed.
  if (full) {
    full_ = true;
    mask_ = {};
  }
}

bool FootprintIndex::contains_third(std::int64_t sum_col, std::int64_t sum_row) const {
  const std::int64_t c = floor_div3(sum_col);
  const std::int64_t r = floor_div3(sum_row);
  if (c < 0 || r < 0 || c + 1 >= width_ || r + 1 >= height_) return false;
  if (full_) return true;
  return square_contains(mask_[static_cast<std::size_t>(r * width_ + c)],
                         static_cast<int>(sum_col - 3 * c), static_cast<int>(sum_row - 3 * r));
}

double footprint_area_cells(const HeightGrid& grid) {
  double area = 0.0;
  for (int r = 0; r + 1 < grid.height; ++r) {
    for (int c = 0; c + 1 < grid.width; ++c) {
      const int n = popcount4(square_mask(grid, c, r));
      area += n == 4 ? 1.0 : n == 3 ? 0.5 : 0.0;
    }
  }
  return area;
}

}  // namespace dpts::core

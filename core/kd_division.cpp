// k-d division of a DEM into pieces of about equal surface-vertex counts.
#include "core/kd_division.hpp"

#include <algorithm>
#include <cstdlib>

#include "core/grid.hpp"

namespace dpts::core {
namespace {

struct Region {
  int bx0, by0, bx1, by1;  // blocks [bx0, bx1) x [by0, by1)
};

}  // namespace

std::size_t piece_bytes(const Piece& piece, int halo) {
  const std::size_t w = static_cast<std::size_t>(piece.width) + 2 * halo;
  const std::size_t h = static_cast<std::size_t>(piece.height) + 2 * halo;
  // Context vertices are triangulated too: count the halo's share of vertices.
  const double area = static_cast<double>(piece.width) * piece.height;
  const double vertices = area > 0 ? piece.vertices * (w * h / area) : 0.0;
  return w * h * kBytesPerWindowCell + static_cast<std::size_t>(vertices * kBytesPerVertex);
}

std::vector<Piece> kd_divide(const BlockCounts& bc, const DivisionOptions& options) {
  // Each split scans its region's blocks: the block grid is small (the caller sizes blocks so
  // that there are at most about a million), and the k-d tree has few levels.
  auto count = [&](const Region& r) {
    std::size_t n = 0;
    for (int by = r.by0; by < r.by1; ++by) {
      for (int bx = r.bx0; bx < r.bx1; ++bx) n += bc.at(bx, by);
    }
    return n;
  };
  auto to_piece = [&](const Region& r, std::size_t n) {
    Piece p;
    p.col0 = r.bx0 * bc.block;
    p.row0 = r.by0 * bc.block;
    p.width = std::min(bc.width, r.bx1 * bc.block) - p.col0;
    p.height = std::min(bc.height, r.by1 * bc.block) - p.row0;
    p.vertices = n;
    return p;
  };
  std::vector<Piece> out;
  struct Item {
    Region region;
    int depth;
  };
  std::vector<Item> stack{{{0, 0, bc.blocks_x, bc.blocks_y}, 0}};
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    const Region& r = item.region;
    const std::size_t n = count(r);
    if (n == 0) continue;
    const Piece piece = to_piece(r, n);
    // note: a window (the piece and its halo) is a core grid, indexed in 32 bits.
    const double window_cells = (static_cast<double>(piece.width) + 2 * options.halo) *
                                (static_cast<double>(piece.height) + 2 * options.halo);
    const bool want = item.depth < options.levels ||
                      window_cells >= static_cast<double>(kMaxGridCells) ||
                      piece_bytes(piece, options.halo) > options.budget_bytes ||
                      (options.max_vertices > 0 && n > options.max_vertices);
    const int nx = r.bx1 - r.bx0, ny = r.by1 - r.by0;
    if (!want || (nx < 2 && ny < 2)) {
      out.push_back(piece);
      continue;
    }
    // Across the longer side (in metres), unless it is one block.
    bool split_cols = piece.width * options.col_metres >= piece.height * options.row_metres;
    if (split_cols && nx < 2) split_cols = false;
    if (!split_cols && ny < 2) split_cols = true;
    // Counts per block line along the split axis, and the line that best halves them.
    const int lines = split_cols ? nx : ny;
    std::vector<std::size_t> per(static_cast<std::size_t>(lines), 0);
    for (int by = r.by0; by < r.by1; ++by) {
      for (int bx = r.bx0; bx < r.bx1; ++bx) {
        per[static_cast<std::size_t>(split_cols ? bx - r.bx0 : by - r.by0)] += bc.at(bx, by);
      }
    }
    int best = 1;
    std::size_t best_diff = static_cast<std::size_t>(-1), below = 0;
    for (int k = 1; k < lines; ++k) {
      below += per[static_cast<std::size_t>(k - 1)];
      const std::size_t above = n - below;
      const std::size_t diff = below > above ? below - above : above - below;
      if (diff < best_diff) best_diff = diff, best = k;
    }
    Region a = r, b = r;
    if (split_cols) {
      a.bx1 = b.bx0 = r.bx0 + best;
    } else {
      a.by1 = b.by0 = r.by0 + best;
    }
    // Second half pushed first so that pieces come out in k-d (first half first) order.
    stack.push_back({b, item.depth + 1});
    stack.push_back({a, item.depth + 1});
  }
  return out;
}

}  // namespace dpts::core

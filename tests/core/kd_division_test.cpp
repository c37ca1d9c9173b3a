// k-d division into pieces: equal counts, exact cover of the raster, budgets, empty blocks.
#include "core/kd_division.hpp"

#include <catch2/catch.hpp>
#include <numeric>

using namespace dpts;

namespace {

core::BlockCounts uniform_counts(int width, int height, int block) {
  core::BlockCounts bc;
  bc.width = width;
  bc.height = height;
  bc.block = block;
  bc.blocks_x = (width + block - 1) / block;
  bc.blocks_y = (height + block - 1) / block;
  for (int by = 0; by < bc.blocks_y; ++by) {
    for (int bx = 0; bx < bc.blocks_x; ++bx) {
      const int w = std::min(block, width - bx * block), h = std::min(block, height - by * block);
      bc.counts.push_back(static_cast<std::uint32_t>(w * h));
    }
  }
  return bc;
}

// Every cell of the raster lies in exactly one piece.
void check_cover(const std::vector<core::Piece>& pieces, int width, int height) {
  std::vector<int> hits(static_cast<std::size_t>(width) * height, 0);
  for (const auto& p : pieces) {
    for (int r = p.row0; r < p.row0 + p.height; ++r) {
      for (int c = p.col0; c < p.col0 + p.width; ++c)
        ++hits[static_cast<std::size_t>(r) * width + c];
    }
  }
  CHECK(std::count(hits.begin(), hits.end(), 1) == static_cast<long>(hits.size()));
}

}  // namespace

TEST_CASE("k-d division of a uniform raster: 2^levels pieces of equal counts", "[core][kd]") {
  const auto bc = uniform_counts(256, 128, 16);
  core::DivisionOptions opt;
  opt.levels = 4;
  opt.budget_bytes = std::size_t{1} << 40;
  const auto pieces = core::kd_divide(bc, opt);
  REQUIRE(pieces.size() == 16);
  for (const auto& p : pieces) {
    CHECK(p.vertices == 256u * 128u / 16u);
    // Always across the longer side (columns on a tie): 256x128 -> 128x128 -> 64x128 -> 64x64
    // -> 32x64.
    CHECK(p.width == 32);
    CHECK(p.height == 64);
  }
  check_cover(pieces, 256, 128);
  // The first piece is the top-left one (k-d order, first half first).
  CHECK(pieces.front().col0 == 0);
  CHECK(pieces.front().row0 == 0);
}

TEST_CASE("k-d division splits across the longer side in metres, not in cells", "[core][kd]") {
  const auto bc = uniform_counts(64, 64, 16);
  core::DivisionOptions opt;
  opt.levels = 1;
  opt.budget_bytes = std::size_t{1} << 40;
  opt.col_metres = 1;
  opt.row_metres = 3;  // rows are three times as long: split the rows
  const auto pieces = core::kd_divide(bc, opt);
  REQUIRE(pieces.size() == 2);
  CHECK(pieces[0].width == 64);
  CHECK(pieces[0].height == 32);
}

TEST_CASE("k-d division goes deeper until every piece fits the budget", "[core][kd]") {
  const auto bc = uniform_counts(512, 512, 16);
  core::DivisionOptions opt;
  opt.levels = 2;
  opt.halo = 8;
  opt.budget_bytes = 8u << 20;
  const auto pieces = core::kd_divide(bc, opt);
  CHECK(pieces.size() > 4);
  for (const auto& p : pieces) CHECK(core::piece_bytes(p, opt.halo) <= opt.budget_bytes);
  check_cover(pieces, 512, 512);
  const std::size_t total =
      std::accumulate(pieces.begin(), pieces.end(), std::size_t{0},
                      [](std::size_t s, const core::Piece& p) { return s + p.vertices; });
  CHECK(total == 512u * 512u);
}

TEST_CASE("k-d division splits at the median of uneven counts and drops empty pieces",
          "[core][kd]") {
  // Valid data only in the left quarter of the columns (a DEM that is mostly sea).
  auto bc = uniform_counts(256, 64, 16);
  for (int by = 0; by < bc.blocks_y; ++by) {
    for (int bx = 4; bx < bc.blocks_x; ++bx)
      bc.counts[static_cast<std::size_t>(by) * bc.blocks_x + bx] = 0;
  }
  core::DivisionOptions opt;
  opt.levels = 1;
  opt.budget_bytes = std::size_t{1} << 40;
  const auto pieces = core::kd_divide(bc, opt);
  REQUIRE(pieces.size() == 2);
  CHECK(pieces[0].vertices == pieces[1].vertices);
  CHECK(pieces[0].col0 + pieces[0].width == 32);  // the median of the valid columns
  CHECK(pieces[1].col0 + pieces[1].width == 256);
  opt.levels = 3;
  for (const auto& p : core::kd_divide(bc, opt)) CHECK(p.vertices > 0);
}

TEST_CASE("a piece whose window would reach 2^32 cells is split, whatever the budget",
          "[core][kd]") {
  // 100000 x 100000 cells in blocks of 1000, surface in two far corners only; no levels, no
  // vertex cap, a budget that takes anything: only the 32-bit window rule splits.
  core::BlockCounts bc;
  bc.width = bc.height = 100000;
  bc.block = 1000;
  bc.blocks_x = bc.blocks_y = 100;
  bc.counts.assign(100 * 100, 0);
  bc.counts[0] = 50;
  bc.counts[100 * 100 - 1] = 70;
  core::DivisionOptions o;
  o.levels = 0;
  o.budget_bytes = ~std::size_t{0};
  o.halo = 1;
  const auto pieces = core::kd_divide(bc, o);
  REQUIRE(pieces.size() >= 2);
  std::size_t vertices = 0;
  for (const auto& p : pieces) {
    vertices += p.vertices;
    const double window = (p.width + 2.0) * (p.height + 2.0);
    CHECK(window < 4294967295.0);
  }
  CHECK(vertices == 120);
  // A raster under 2^32 cells keeps one piece.
  bc.width = bc.height = 60000;
  bc.blocks_x = bc.blocks_y = 60;
  bc.counts.assign(60 * 60, 0);
  bc.counts[0] = 50;
  bc.counts[60 * 60 - 1] = 70;
  CHECK(core::kd_divide(bc, o).size() == 1);
}

// Per-piece budgets of PLD'/VP': the paper's formula, clamping, exact totals.
#include "core/piece_budget.hpp"

#include <catch2/catch.hpp>
#include <numeric>

using dpts::core::largest_remainder;
using dpts::core::piece_budgets;

TEST_CASE("equal piece values give every piece the overall percentage", "[core][budget]") {
  const auto b = piece_budgets({1000, 1000, 1000, 1000}, {0.9, 0.9, 0.9, 0.9}, 10.0);
  CHECK(b == std::vector<std::size_t>{100, 100, 100, 100});
}

TEST_CASE("budgets follow the paper's formula by hand", "[core][budget]") {
  // values 1 and 0.5: S = 1.25, m = 2, P2L = 50:
  //   piece 0: 100 - (1/1.25) * 2 * 50 = 20 %  -> 200 of 1000
  //   piece 1: 100 - (0.25/1.25) * 2 * 50 = 80 % -> 800 of 1000
  const auto b = piece_budgets({1000, 1000}, {1.0, 0.5}, 50.0);
  CHECK(b == std::vector<std::size_t>{200, 800});
}

TEST_CASE("clamped pieces hand their excess to the others and the total stays exact",
          "[core][budget]") {
  // values 1 and 0.2 at P2L 10: piece 0 would get 100 - (1/1.04)*2*90 < 0 %: clamped to 3.
  const std::vector<std::size_t> counts = {5000, 3000, 1234};
  const auto b = piece_budgets(counts, {1.0, 0.2, 0.6}, 10.0);
  CHECK(std::accumulate(b.begin(), b.end(), std::size_t{0}) == 923);  // round(0.1 * 9234)
  CHECK(b[0] >= 3);
  for (std::size_t i = 0; i < b.size(); ++i) CHECK(b[i] <= counts[i]);
}

TEST_CASE("budgets never exceed a piece and reach 100 % exactly", "[core][budget]") {
  const auto b = piece_budgets({10, 20, 30}, {0.99, 0.5, 0.7}, 100.0);
  CHECK(b == std::vector<std::size_t>{10, 20, 30});
}

TEST_CASE("largest remainder rounding hits the total exactly, within caps", "[core][budget]") {
  // 10 split 1/3 : 1/3 : 1/3 -> 4, 3, 3 (ties to the lower index).
  CHECK(largest_remainder({10.0 / 3, 10.0 / 3, 10.0 / 3}, 10, {10, 10, 10}) ==
        std::vector<std::size_t>{4, 3, 3});
  // Largest remainders first: 1.2, 2.7, 3.1 -> 1, 3, 3 for a total of 7.
  CHECK(largest_remainder({1.2, 2.7, 3.1}, 7, {5, 5, 5}) == std::vector<std::size_t>{1, 3, 3});
  // A cap stops a piece; the next remainder gets the unit.
  CHECK(largest_remainder({1.2, 2.7, 3.1}, 7, {5, 2, 5}) == std::vector<std::size_t>{2, 2, 3});
  // Caps too small for the total: as close as they allow.
  CHECK(largest_remainder({2.5, 2.5}, 5, {2, 2}) == std::vector<std::size_t>{2, 2});
}

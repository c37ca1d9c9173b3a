// Per-piece vertex budgets of the meta method PLD'/VP' (the DPTS paper, section 4.3):
//   P2L_i = 100 - value_i^2 / S * m * (100 - P2L),   S = sum of value_j^2 over the m pieces,
// where value_i is the piece's mean ED/GD ratio. Flat pieces (value near 1) keep fewer vertices.
#pragma once

#include <cstddef>
#include <vector>

namespace dpts::core {

// Vertices each piece keeps: the paper's formula, clamped so that a piece keeps at least
// min_keep (and at least 0 %) and at most all of its vertices, with what clamping frees or
// needs spread over the other pieces in proportion to their room, and rounded by largest
// remainder so that the total is exactly round(P2L / 100 * sum of counts) (never below the sum
// of the minimums). Deterministic: ties in remainders go to the lower piece index.
// counts[i] > 0 vertices of piece i; values[i] > 0; p2l in (0, 100].
std::vector<std::size_t> piece_budgets(const std::vector<std::size_t>& counts,
                                       const std::vector<double>& values, double p2l,
                                       std::size_t min_keep = 3);

// Integer parts of non-negative `shares` that add up to exactly `total`: each share rounded
// down (after a 1e-9 nudge against rounding), then one more to the largest remainders (ties to
// the lower index), never above its cap. Fewer than `total` only when the caps do not allow it.
std::vector<std::size_t> largest_remainder(const std::vector<double>& shares, std::size_t total,
                                           const std::vector<std::size_t>& caps);

}  // namespace dpts::core

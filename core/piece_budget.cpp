// Per-piece budgets of PLD'/VP' (the DPTS paper, section 4.3) with exact totals.
#include "core/piece_budget.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace dpts::core {

std::vector<std::size_t> piece_budgets(const std::vector<std::size_t>& counts,
                                       const std::vector<double>& values, double p2l,
                                       std::size_t min_keep) {
  const std::size_t m = counts.size();
  if (values.size() != m || m == 0)
    throw std::invalid_argument("piece_budgets: counts and values differ");
  const double total_n =
      static_cast<double>(std::accumulate(counts.begin(), counts.end(), std::size_t{0}));
  double s = 0;
  for (double v : values) s += v * v;
  // Lower and upper bounds per piece, and the exact total to reach.
  std::vector<double> lo(m), hi(m), want(m);
  double lo_sum = 0;
  for (std::size_t i = 0; i < m; ++i) {
    hi[i] = static_cast<double>(counts[i]);
    lo[i] = std::min(hi[i], static_cast<double>(min_keep));
    lo_sum += lo[i];
    const double share = s > 0 ? values[i] * values[i] / s : 1.0 / m;
    const double pct = 100.0 - share * m * (100.0 - p2l);
    want[i] = pct / 100.0 * hi[i];
  }
  const double target = std::clamp(std::round(p2l / 100.0 * total_n), lo_sum, total_n);
  // Clamp, then move the excess or deficit onto the unclamped pieces in proportion to their
  // room, until nothing moves (at most m rounds: each round clamps at least one more piece).
  std::vector<double> keep(m);
  for (std::size_t i = 0; i < m; ++i) keep[i] = std::clamp(want[i], lo[i], hi[i]);
  for (std::size_t round = 0; round <= m; ++round) {
    const double diff = target - std::accumulate(keep.begin(), keep.end(), 0.0);
    if (std::fabs(diff) < 1e-9) break;
    double room = 0;
    for (std::size_t i = 0; i < m; ++i) room += diff > 0 ? hi[i] - keep[i] : keep[i] - lo[i];
    if (room <= 0) break;
    for (std::size_t i = 0; i < m; ++i) {
      const double r = diff > 0 ? hi[i] - keep[i] : keep[i] - lo[i];
      keep[i] = std::clamp(keep[i] + diff * r / room, lo[i], hi[i]);
    }
  }
  return largest_remainder(keep, static_cast<std::size_t>(target), counts);
}

std::vector<std::size_t> largest_remainder(const std::vector<double>& shares, std::size_t total,
                                           const std::vector<std::size_t>& caps) {
  const std::size_t m = shares.size();
  std::vector<std::size_t> out(m);
  std::vector<std::pair<double, std::size_t>> rest;
  std::size_t sum = 0;
  for (std::size_t i = 0; i < m; ++i) {
    out[i] = std::min(caps[i], static_cast<std::size_t>(std::floor(shares[i] + 1e-9)));
    sum += out[i];
    rest.emplace_back(shares[i] - static_cast<double>(out[i]), i);
  }
  std::sort(rest.begin(), rest.end(), [](const auto& a, const auto& b) {
    return a.first > b.first || (a.first == b.first && a.second < b.second);
  });
  for (std::size_t k = 0; sum < total && k < rest.size(); ++k) {
    const std::size_t i = rest[k].second;
    if (out[i] < caps[i]) ++out[i], ++sum;
  }
  return out;
}

}  // namespace dpts::core

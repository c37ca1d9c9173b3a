// VP and PLD importance on hand-made stars, against hand-computed values.
#include "core/importance.hpp"

#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <vector>

using dpts::core::LinkTriangle;
using dpts::core::Point3;
using dpts::core::Star;

namespace {

// Square link (1,0) (0,1) (-1,0) (0,-1) round an apex at the origin, ccw.
std::vector<Point3> square_link(double z0, double z1, double z2, double z3) {
  return {{1, 0, z0}, {0, 1, z1}, {-1, 0, z2}, {0, -1, z3}};
}
// The hole refilled along the diagonal link[0]-link[2].
const std::vector<LinkTriangle> kSplit02 = {{0, 1, 2}, {0, 2, 3}};

// Uniform numbers in [0, 1) from a seed (a 64-bit LCG's top 53 bits): the same stars on every
// machine.
struct Uniform {
  std::uint64_t state;
  double operator()() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  }
};

}  // namespace

TEST_CASE("removing a vertex of a plane has VP importance 0", "[core][importance][vp]") {
  // Plane z = 2x + 3y + 1 through apex and link.
  auto plane = [](double x, double y) { return 2 * x + 3 * y + 1; };
  std::vector<Point3> link;
  for (auto [x, y] : std::vector<std::pair<double, double>>{{1, 0}, {0, 1}, {-1, 0}, {0, -1}}) {
    link.push_back({x, y, plane(x, y)});
  }
  const Star star{{0, 0, plane(0, 0)}, link.data(), link.size(), true};
  CHECK(dpts::core::vp_volume_exact(star, kSplit02) == Approx(0.0).margin(1e-12));
  CHECK(dpts::core::vp_volume_monte_carlo(star, kSplit02, 1000, 7) == 0.0);
}

TEST_CASE("VP of a pyramid apex is the pyramid's volume", "[core][importance][vp]") {
  // Apex at height h over a flat square of area 2: volume = 2 h / 3.
  const double h = 3.0;
  const auto link = square_link(0, 0, 0, 0);
  const Star star{{0, 0, h}, link.data(), link.size(), true};
  CHECK(dpts::core::vp_volume_exact(star, kSplit02) == Approx(2.0 * h / 3.0).epsilon(1e-12));
  // The paper's Monte Carlo estimate converges to the same value.
  CHECK(dpts::core::vp_volume_monte_carlo(star, kSplit02, 200000, 11) ==
        Approx(2.0 * h / 3.0).epsilon(0.02));
}

TEST_CASE("VP integrates |difference| where the surfaces cross", "[core][importance][vp]") {
  // Link heights +1, -1, +1, -1 round an apex at 0: the fan is z = |x| - |y|; refilled along
  // link 0-2 it becomes z = 1 - 2|y|. The difference |x| + |y| - 1 is <= 0 on the diamond, so
  // the volume is the integral of 1 - |x| - |y|: 1/6 per quadrant, 2/3 in all.
  const auto link = square_link(1, -1, 1, -1);
  const Star star{{0, 0, 0}, link.data(), link.size(), true};
  const double exact = dpts::core::vp_volume_exact(star, kSplit02);
  // An independent computation: a dense Monte Carlo estimate.
  CHECK(dpts::core::vp_volume_monte_carlo(star, kSplit02, 400000, 3) ==
        Approx(exact).epsilon(0.02));
  CHECK(exact == Approx(2.0 / 3.0).epsilon(1e-12));
}

TEST_CASE("Monte Carlo VP is deterministic for a seed", "[core][importance][vp]") {
  const auto link = square_link(0.5, 0, 0.2, 0);
  const Star star{{0, 0, 1}, link.data(), link.size(), true};
  CHECK(dpts::core::vp_volume_monte_carlo(star, kSplit02, 100, 42) ==
        dpts::core::vp_volume_monte_carlo(star, kSplit02, 100, 42));
}

TEST_CASE("PLD importance is 0 on a plane with a convex link", "[core][importance][pld]") {
  const auto link = square_link(0, 0, 0, 0);
  const Star star{{0, 0, 0}, link.data(), link.size(), true};
  CHECK(dpts::core::pld_importance(star) == Approx(0.0).margin(1e-12));
}

TEST_CASE("PLD of a pyramid apex matches the unfolded geodesic", "[core][importance][pld]") {
  // Apex height 1 over the square link: opposite link vertices are 2 apart; the fan unfolds
  // to two faces of 60 degrees each at the apex with edges sqrt(2), so GD = sqrt(6).
  const auto link = square_link(0, 0, 0, 0);
  const Star star{{0, 0, 1}, link.data(), link.size(), true};
  CHECK(dpts::core::pld_importance(star) == Approx(1.0 - 2.0 / std::sqrt(6.0)).epsilon(1e-12));
}

TEST_CASE("PLD goes round a link vertex that pokes towards the apex", "[core][importance][pld]") {
  // Flat star whose link vertex 1 sits close to the apex: the straight segment from link 0
  // to link 2 leaves the fan, so the path bends at link 1.
  std::vector<Point3> link = {{1, 0, 0}, {0.1, 0.1, 0}, {0, 1, 0}, {-1, -1, 0}};
  const Star star{{0, 0, 0}, link.data(), link.size(), true};
  const double bent = std::hypot(0.9, 0.1) + std::hypot(0.1, 0.9);
  // Pairs (0,2): ED sqrt(2) over GD = min(bent, other way round); the other way round
  // passes the apex side: 0 -> 3 -> 2 is a fan of angle 270 degrees, so it goes via the apex
  // with length 2.
  const double ratio02 = std::sqrt(2.0) / std::min(bent, 2.0);
  // Pair (1,3): ED = sqrt(1.1^2 * 2), via the apex (180 degrees both ways) = 0.1*sqrt2 + sqrt2.
  const double ratio13 = std::sqrt(2 * 1.1 * 1.1) / (0.1 * std::sqrt(2.0) + std::sqrt(2.0));
  CHECK(dpts::core::pld_importance(star) ==
        Approx(1.0 - std::min(ratio02, ratio13)).epsilon(1e-12));
}

TEST_CASE("VP's lower bound is below the exact volume, and equal where one surface is above",
          "[core][importance][vp]") {
  // A pyramid: the fan lies wholly above the refill, so the bound is the volume (less its
  // rounding margin, a relative 1e-9 here).
  const auto flat = square_link(0, 0, 0, 0);
  const Star pyramid{{0, 0, 3.0}, flat.data(), flat.size(), true};
  CHECK(dpts::core::vp_volume_bound(pyramid, kSplit02) == Approx(2.0).epsilon(1e-8));
  CHECK(dpts::core::vp_volume_bound(pyramid, kSplit02) <=
        dpts::core::vp_volume_exact(pyramid, kSplit02));
  // The case above whose surfaces cross along the link: the refill is wholly above the fan.
  const auto saddle = square_link(1, -1, 1, -1);
  const Star crossing{{0, 0, 0}, saddle.data(), saddle.size(), true};
  CHECK(dpts::core::vp_volume_bound(crossing, kSplit02) == Approx(2.0 / 3.0).epsilon(1e-8));
  // Random stars of 3 to 12 link vertices at heights far from 0 (rounding margins matter
  // there), refilled as a fan from link[0]: never above the exact volume.
  Uniform uniform{12345};
  int tight = 0, loose = 0;
  for (int k = 0; k < 2000; ++k) {
    const int n = 3 + k % 10;
    const double base = 4000.0 * uniform(), relief = k % 3 == 0 ? 1e-3 : 50.0;
    std::vector<Point3> link;
    for (int i = 0; i < n; ++i) {
      // A convex link (angles in order, radii 0.8 to 1.2 of a 30 m cell), so a fan from
      // link[0] stays inside it.
      const double a = 2.0 * M_PI * (i + 0.5 * uniform()) / n;
      const double r = 30.0 * (1.0 + 0.2 * (uniform() - 0.5)) * (i % 2 == 0 ? 1.0 : 0.98);
      link.push_back({1e5 + r * std::cos(a), 2e5 + r * std::sin(a), base + relief * uniform()});
    }
    std::vector<LinkTriangle> fan;
    for (int i = 1; i + 1 < n; ++i) fan.push_back({0, i, i + 1});
    const Star star{{1e5, 2e5, base + relief * (uniform() - 0.25)}, link.data(), link.size(), true};
    const double bound = dpts::core::vp_volume_bound(star, fan);
    const double exact = dpts::core::vp_volume_exact(star, fan);
    INFO("star " << k);
    CHECK(bound >= 0.0);
    CHECK(bound <= exact);
    tight += bound >= 0.9 * exact;
    loose += bound < 0.5 * exact;
  }
  CHECK(tight > 200);  // a real bound, not 0
  CHECK(loose > 200);  // where the surfaces cross inside, below the volume
}

namespace {

// PLD as the fan's unfolding was first written: each pair's fan unfolded by the cosine and sine
// of its summed apex angles (atan2 of each), the path through the apex from a sum of pi on,
// else the taut string round the link vertices that poke towards the apex.
double pld_by_angles(const Star& s) {
  const std::size_t n = s.n;
  auto sub = [](const Point3& a, const Point3& b) {
    return std::array<double, 3>{a.x - b.x, a.y - b.y, a.z - b.z};
  };
  auto len = [](std::array<double, 3> v) {
    return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  };
  std::vector<double> radius(n), angle(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) radius[i] = len(sub(s.link[i], s.apex));
  const std::size_t fans = s.closed ? n : n - 1;
  for (std::size_t i = 0; i < fans; ++i) {
    const auto a = sub(s.link[i], s.apex), b = sub(s.link[(i + 1) % n], s.apex);
    const std::array<double, 3> c{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                                  a[0] * b[1] - a[1] * b[0]};
    angle[i] = std::atan2(len(c), a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
  }
  // The path over `steps` fan triangles from link[from] (dir +1: counter-clockwise).
  auto gd = [&](std::size_t from, std::size_t steps, int dir) {
    std::vector<std::array<double, 2>> chain{{radius[from], 0.0}};
    double total = 0.0;
    std::size_t idx = from;
    for (std::size_t k = 1; k <= steps; ++k) {
      total += angle[dir > 0 ? idx : (idx + n - 1) % n];
      idx = dir > 0 ? (idx + 1) % n : (idx + n - 1) % n;
      chain.push_back({radius[idx] * std::cos(total), radius[idx] * std::sin(total)});
    }
    if (total >= M_PI) return radius[from] + radius[idx];
    std::size_t h = 0;
    auto turn = [](auto o, auto a, auto b) {
      return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    };
    for (std::size_t k = 0; k < chain.size(); ++k) {
      while (h >= 2 && turn(chain[h - 2], chain[h - 1], chain[k]) >= 0) --h;
      chain[h++] = chain[k];
    }
    double sum = 0.0;
    for (std::size_t k = 1; k < h; ++k) {
      sum += std::hypot(chain[k][0] - chain[k - 1][0], chain[k][1] - chain[k - 1][1]);
    }
    return sum;
  };
  double ratio = 1.0;
  for (std::size_t i = 0; i + 2 < n; ++i) {
    for (std::size_t j = i + 2; j < n; ++j) {
      if (s.closed && i == 0 && j == n - 1) continue;
      double g = gd(i, j - i, +1);
      if (s.closed) g = std::min(g, gd(i, n - (j - i), -1));
      if (g > 0) ratio = std::min(ratio, len(sub(s.link[i], s.link[j])) / g);
    }
  }
  return 1.0 - ratio;
}

}  // namespace

TEST_CASE("PLD unfolded by rotations is PLD unfolded by summed angles", "[core][importance][pld]") {
  // Random stars of 3 to 14 link vertices, closed and open (on the outline), flat to steep
  // (fans of 2 pi and far more, so that paths run through the apex), and link vertices poking
  // towards the apex.
  Uniform uniform{777};
  int through_apex = 0, bent = 0;
  for (int k = 0; k < 3000; ++k) {
    const int n = 3 + k % 12;
    const bool closed = k % 4 != 0;
    const double relief = k % 5 == 0 ? 0.0 : k % 5 == 1 ? 5.0 : 60.0;
    std::vector<Point3> link;
    for (int i = 0; i < n; ++i) {
      const double a = (closed ? 2.0 : 1.5) * M_PI * (i + 0.8 * uniform()) / n;
      const double r = 30.0 * (i % 3 == 1 && k % 2 == 0 ? 0.15 + 0.3 * uniform() : 1.0);
      link.push_back({r * std::cos(a), r * std::sin(a), relief * (uniform() - 0.5)});
    }
    const Star star{{0, 0, relief * (uniform() - 0.5)}, link.data(), link.size(), closed};
    const double reference = pld_by_angles(star);
    INFO("star " << k);
    CHECK(dpts::core::pld_importance(star) == Approx(reference).margin(1e-12));
    through_apex += reference > 0.2;
    bent += reference > 0.01 && reference < 0.2;
  }
  CHECK(through_apex > 100);
  CHECK(bent > 100);
}

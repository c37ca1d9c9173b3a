// PairRoutes: the routes read back are those stored, from memory or from the temporary file.
#include "parallel/pair_routes.hpp"

#include <tbb/parallel_for.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

using namespace dpts;
using Points = std::vector<std::array<double, 2>>;

// Route i -> j of pair test k points: i + j + 1 bends, 2 (i + j) taut points, on a line.
core::PathRoute route_of(std::size_t i, std::size_t j) {
  core::PathRoute r;
  for (std::size_t n = 0; n < i + j + 1; ++n) r.bends.push_back({1000.0 + i + 0.5 * n, 2000.0 + j});
  for (std::size_t n = 0; n < 2 * (i + j); ++n) r.taut.push_back({1000.0 - n, 2000.0 + i * j});
  return r;
}

// What get() gives for the route i -> j stored as pair min < max: from the lower point, as
// floats from the origin, then the end.
Points expected(const Points& from, bool reversed, const std::array<double, 2>& origin,
                const std::array<double, 2>& end) {
  Points out;
  auto as_float = [&](const std::array<double, 2>& p) {
    return std::array<double, 2>{origin[0] + static_cast<float>(p[0] - origin[0]),
                                 origin[1] + static_cast<float>(p[1] - origin[1])};
  };
  for (std::size_t n = 0; n < from.size(); ++n)
    out.push_back(as_float(from[reversed ? from.size() - 1 - n : n]));
  out.push_back(as_float(end));
  return out;
}

// Stores every pair of k points (the upper ones from the far end, reversed), in parallel,
// then checks each one read back.
void store_and_check(par::PairRoutes& routes, std::size_t k) {
  const std::array<double, 2> origin{1000.25, 2000.75};
  routes.reset(k, origin);
  auto end_of = [](std::size_t b) { return std::array<double, 2>{3000.0 + b, 4000.0 - b}; };
  tbb::parallel_for(std::size_t{0}, k, [&](std::size_t a) {
    for (std::size_t b = a + 1; b < k; ++b) {
      // note: odd pairs stored from b to a, with an unused candidate first
      const bool reversed = (a + b) % 2 == 1;
      routes.add(route_of(b, a), !reversed, end_of(b));
      const auto id = reversed ? routes.add(route_of(b, a), true, end_of(b))
                               : routes.add(route_of(a, b), false, end_of(b));
      if (b != a + 1) routes.assign(a, b, id);  // note: neighbours get none
    }
  });
  Points bends, taut;
  for (std::size_t a = 0; a < k; ++a) {
    for (std::size_t b = a + 1; b < k; ++b) {
      CAPTURE(a, b);
      if (b == a + 1) {
        CHECK_FALSE(routes.get(a, b, bends, taut));
        CHECK(bends.empty());
        continue;
      }
      REQUIRE(routes.get(a, b, bends, taut));
      const bool reversed = (a + b) % 2 == 1;
      const auto r = reversed ? route_of(b, a) : route_of(a, b);
      CHECK(bends == expected(r.bends, reversed, origin, end_of(b)));
      CHECK(taut == expected(r.taut, reversed, origin, end_of(b)));
    }
  }
  CHECK_FALSE(routes.get(k, k + 1, bends, taut));  // beyond the points: none
}

}  // namespace

TEST_CASE("routes read back as stored, in memory and from the temporary file",
          "[parallel][evaluate][routes]") {
  par::PairRoutes in_memory(std::size_t{64} << 20);
  store_and_check(in_memory, 30);
  CHECK(in_memory.spilled_bytes() == 0);
  CHECK(in_memory.memory_bytes() > 0);
  // No memory: every route but the last in the file.
  par::PairRoutes spilled(0);
  store_and_check(spilled, 30);
  CHECK(spilled.spilled_bytes() > 0);
  CHECK(spilled.memory_bytes() < 2000);
  // Some: within it, the rest in the file.
  par::PairRoutes some(10000);
  store_and_check(some, 30);
  CHECK(some.spilled_bytes() > 100000);
  CHECK(some.memory_bytes() <= 10000);
  // A store moved keeps its routes.
  par::PairRoutes moved(std::move(some));
  Points bends, taut;
  CHECK(moved.get(0, 2, bends, taut));
  CHECK(bends.size() == 4);  // 3 bends, then the end
}

TEST_CASE("routes stay in memory where the temporary file cannot be made",
          "[parallel][evaluate][routes]") {
  const char* old = std::getenv("TMPDIR");
  const std::string saved = old ? old : "";
  setenv("TMPDIR", "/nonexistent-dpts-folder", 1);
  par::PairRoutes routes(0);
  store_and_check(routes, 20);
  CHECK(routes.spilled_bytes() == 0);
  if (old) {
    setenv("TMPDIR", saved.c_str(), 1);
  } else {
    unsetenv("TMPDIR");
  }
}

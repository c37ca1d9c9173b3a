// The indexed heap pops in (key, id) order whatever the updates.
#include "core/indexed_heap.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <limits>
#include <random>
#include <tuple>
#include <vector>

TEST_CASE("IndexedMinHeap pops by key, ties by scrambled id, after updates and erasures",
          "[core][heap]") {
  const std::uint32_t n = 500;
  dpts::core::IndexedMinHeap heap(n);
  std::mt19937 rng(5);
  std::vector<double> key(n);
  std::vector<bool> present(n, false);
  std::vector<std::uint32_t> ids;
  std::vector<double> keys;
  for (std::uint32_t i = 0; i < n; i += 2) {
    key[i] = static_cast<double>(rng() % 50);  // many ties
    ids.push_back(i), keys.push_back(key[i]), present[i] = true;
  }
  heap.assign(ids, keys);
  for (int step = 0; step < 2000; ++step) {
    const std::uint32_t id = rng() % n;
    if (rng() % 4 == 0) {
      heap.erase(id);
      present[id] = false;
    } else {
      key[id] = static_cast<double>(rng() % 50);
      heap.set(id, key[id]);
      present[id] = true;
    }
  }
  using Heap = dpts::core::IndexedMinHeap;
  std::vector<std::tuple<double, std::uint32_t, std::uint32_t>> expected;  // key, scramble, id
  for (std::uint32_t i = 0; i < n; ++i) {
    if (present[i]) expected.emplace_back(key[i], Heap::scramble(i), i);
  }
  std::sort(expected.begin(), expected.end());
  REQUIRE(heap.size() == expected.size());
  for (const auto& e : expected) {
    REQUIRE(heap.top_key() == std::get<0>(e));
    REQUIRE(heap.pop() == std::get<2>(e));
  }
  CHECK(heap.empty());
}

TEST_CASE("IndexedMinHeap orders any size at once, the smallest included", "[core][heap]") {
  for (std::uint32_t n = 0; n < 12; ++n) {
    INFO(n);
    dpts::core::IndexedMinHeap heap(n);
    for (std::uint32_t i = 0; i < n; ++i) heap.push_unordered(i, static_cast<double>((7 * i) % n));
    heap.heapify();
    std::vector<double> popped;
    while (!heap.empty()) {
      popped.push_back(heap.top_key());
      heap.pop();
    }
    CHECK(popped.size() == n);
    CHECK(std::is_sorted(popped.begin(), popped.end()));
  }
}

TEST_CASE("IndexedMinHeap orders negative, zero and infinite keys as doubles compare",
          "[core][heap]") {
  // The keys are kept as integers of the same order: -0 ties with +0 (broken by the id's
  // scramble), and top_key gives each key back.
  using Heap = dpts::core::IndexedMinHeap;
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> key = {3.5,  -0.0, 0.0,   -inf, 1e-300, -1e-300, inf,
                                   -2.0, 2.0,  1e300, -0.0, 0.0,    7.25,    -7.25};
  const auto n = static_cast<std::uint32_t>(key.size());
  Heap heap(n);
  for (std::uint32_t i = 0; i < n; ++i) heap.set(i, i % 2 ? 0.0 : key[i]);
  for (std::uint32_t i = 1; i < n; i += 2) heap.set(i, key[i]);  // changed after insertion
  std::vector<std::tuple<double, std::uint32_t, std::uint32_t>> expected;
  for (std::uint32_t i = 0; i < n; ++i) expected.emplace_back(key[i], Heap::scramble(i), i);
  std::sort(expected.begin(), expected.end());  // tuple order: -0.0 == 0.0, as the heap's
  for (const auto& e : expected) {
    REQUIRE(heap.top_key() == std::get<0>(e));
    REQUIRE(heap.pop() == std::get<2>(e));
  }
  CHECK(heap.empty());
}

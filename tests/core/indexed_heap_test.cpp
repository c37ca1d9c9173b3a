// The indexed heap pops in (key, id) order whatever the updates.
#include "core/indexed_heap.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <set>
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

TEST_CASE("IndexedMinHeap pops as an ordered set does, keys spread over many bands",
          "[core][heap]") {
  // The heap keeps only the lowest band of keys ordered and sets the others aside: keys over
  // 40 binary orders of magnitude, both signs, moved up and down across bands and into the
  // heap, erased from either, pops interleaved; each pop must be the least (key, tie) queued.
  using Heap = dpts::core::IndexedMinHeap;
  for (const unsigned seed : {1u, 2u, 3u}) {
    INFO(seed);
    const std::uint32_t n = 3000;
    Heap heap(n);
    std::mt19937 rng(seed);
    auto draw = [&]() {
      const double mag =
          std::ldexp(1.0 + (rng() % 1000) / 1000.0, static_cast<int>(rng() % 40) - 20);
      switch (rng() % 8) {
        case 0:
          return -mag;
        case 1:
          return 0.0;
        case 2:
          return std::ldexp(static_cast<double>(rng() % 4), -3);  // exact ties
        default:
          return mag;
      }
    };
    using Key = std::tuple<double, std::uint32_t, std::uint32_t>;  // key, scramble, id
    std::set<Key> ref;
    std::vector<double> key(n);
    std::vector<bool> queued(n, false);
    auto unqueue = [&](std::uint32_t id) {
      if (queued[id]) ref.erase(Key{key[id], Heap::scramble(id), id});
      queued[id] = false;
    };
    // A start as the callers make it: unordered, then ordered at once.
    for (std::uint32_t id = 0; id < n; id += 3) {
      key[id] = draw();
      heap.push_unordered(id, key[id]);
      ref.insert(Key{key[id], Heap::scramble(id), id});
      queued[id] = true;
    }
    heap.heapify();
    for (int step = 0; step < 40000; ++step) {
      const std::uint32_t id = rng() % n;
      const unsigned op = rng() % 10;
      if (op < 2) {
        heap.erase(id);
        unqueue(id);
      } else if (op < 4 && !ref.empty()) {
        REQUIRE(heap.top_key() == std::get<0>(*ref.begin()));
        REQUIRE(heap.pop() == std::get<2>(*ref.begin()));
        queued[std::get<2>(*ref.begin())] = false;
        ref.erase(ref.begin());
      } else {
        unqueue(id);
        // note: mostly upwards, as the simplifiers' keys move, sometimes far down
        key[id] = rng() % 4 == 0 ? draw() : std::fabs(draw()) * 4;
        heap.set(id, key[id]);
        ref.insert(Key{key[id], Heap::scramble(id), id});
        queued[id] = true;
      }
      REQUIRE(heap.size() == ref.size());
      REQUIRE(heap.empty() == ref.empty());
      for (std::uint32_t probe : {id, static_cast<std::uint32_t>(rng() % n)}) {
        REQUIRE(heap.contains(probe) == static_cast<bool>(queued[probe]));
      }
    }
    std::vector<double> keys;
    heap.for_each_key([&](double k) { keys.push_back(k); });
    std::vector<double> want;
    for (const Key& k : ref) want.push_back(std::get<0>(k));
    std::sort(keys.begin(), keys.end());
    CHECK(keys == want);
    for (const Key& k : ref) {
      REQUIRE(heap.top_key() == std::get<0>(k));
      REQUIRE(heap.pop() == std::get<2>(k));
    }
    CHECK(heap.empty());
  }
}

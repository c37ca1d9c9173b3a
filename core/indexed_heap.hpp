// A 4-ary min-heap of item ids keyed by (priority, id), with O(log n) update and erase.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace dpts::core {

// Items are ids in [0, capacity). Equal priorities are ordered by a fixed bijective scramble of
// the id, so the order of pops is fully determined by the keys (deterministic tie-breaking).
// note: scrambling, not the plain id, matters for elimination: on flat ground every vertex ties
// at importance 0, and removing them in row-major order sweeps a front across the DEM whose
// vertices gain thousands of neighbours; a scattered order keeps degrees near 6.
class IndexedMinHeap {
 public:
  static constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();

  explicit IndexedMinHeap(std::size_t capacity = 0) : pos_(capacity, kAbsent) {}

  bool empty() const { return heap_.empty(); }
  std::size_t size() const { return heap_.size(); }
  bool contains(std::uint32_t id) const { return pos_[id] != kAbsent; }
  std::uint32_t top() const { return at(0).id; }
  double top_key() const { return decode(at(0).key); }

  // Builds the heap from (id, key) pairs at once, in O(n).
  void assign(const std::vector<std::uint32_t>& ids, const std::vector<double>& keys) {
    heap_.resize(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) place(i, entry(ids[i], keys[i]));
    heapify();
  }

  // Room for n entries (push_unordered's), so that the heap is not copied as it grows.
  void reserve(std::size_t n) { heap_.reserve(n); }

  // Appends (id, key) without ordering (id must be absent); heapify() then orders all at
  // once, in O(n), with no temporary arrays.
  void push_unordered(std::uint32_t id, double key) {
    heap_.push_back(entry(id, key));
    pos_[id] = static_cast<std::uint32_t>(size() - 1);
  }
  void heapify() {
    for (std::size_t i = std::min(size(), size() / kArity + 1); i-- > 0;) sift_down(i, at(i));
  }

  // Hints that id's key will be set soon: its slot (prefetch_slot), then, once that is at
  // hand, its entry and the entry's parent (prefetch), asked for from memory ahead of time.
  void prefetch_slot(std::uint32_t id) const { __builtin_prefetch(&pos_[id]); }
  void prefetch(std::uint32_t id) const {
    const std::uint32_t p = pos_[id];
    if (p == kAbsent) return;
    __builtin_prefetch(&heap_[p]);
    if (p > 0) __builtin_prefetch(&heap_[(p - 1) / kArity]);
  }

  // Inserts id or changes its key.
  void set(std::uint32_t id, double key) {
    if (pos_[id] == kAbsent) {
      heap_.push_back(entry(id, key));
      sift_up(size() - 1, heap_.back());
      return;
    }
    const std::size_t p = pos_[id];
    Entry e = at(p);
    e.key = encode(key);
    if (less(e, at(p))) {
      sift_up(p, e);
    } else {
      sift_down(p, e);
    }
  }

  void erase(std::uint32_t id) {
    const std::uint32_t p = pos_[id];
    if (p == kAbsent) return;
    const Entry last = heap_.back();
    heap_.pop_back();
    pos_[id] = kAbsent;
    if (last.id == id) return;
    if (p > 0 && less(last, at((p - 1) / kArity))) {
      sift_up(p, last);
    } else {
      sift_down(p, last);
    }
  }

  // A bijection of 32-bit ids (MurmurHash3's finaliser): the tie order.
  static std::uint32_t scramble(std::uint32_t x) {
    x ^= x >> 16;
    x *= 0x85EBCA6Bu;
    x ^= x >> 13;
    x *= 0xC2B2AE35u;
    x ^= x >> 16;
    return x;
  }

  // Calls fn(key) for every queued entry, in no particular order.
  template <typename Fn>
  void for_each_key(Fn&& fn) const {
    for (const Entry& e : heap_) fn(decode(e.key));
  }
  std::uint32_t pop() {
    const std::uint32_t id = at(0).id;
    pos_[id] = kAbsent;
    const Entry last = heap_.back();
    heap_.pop_back();
    if (!heap_.empty()) sift_down_from_top(last);
    return id;
  }

 private:
  __extension__ typedef unsigned __int128 U128;  // GCC's and Clang's (no ISO C++ type)
  // note: the key as an unsigned integer of the same order (the double's bits, the sign bit
  // flipped, negatives all flipped; -0 as +0, NaN above +infinity), and the entry laid out so
  // that one unsigned 128-bit comparison orders by (key, tie): sifting chooses among children
  // without branches (the double and tie tests were a third of qem's collapse loop).
  struct Entry {
    std::uint32_t id;   // bits 0-31 of the 128-bit value (ties are unique: never decides)
    std::uint32_t tie;  // bits 32-63
    std::uint64_t key;  // bits 64-127
  };
  static std::uint64_t encode(double key) {
    if (std::isnan(key)) return ~std::uint64_t{0};
    const double k = key + 0.0;  // -0 -> +0: ties, as the doubles compared
    std::uint64_t u;
    std::memcpy(&u, &k, sizeof u);
    return (u >> 63) ? ~u : u | (std::uint64_t{1} << 63);
  }
  static double decode(std::uint64_t u) {
    if (u == ~std::uint64_t{0}) return std::numeric_limits<double>::quiet_NaN();
    u = (u >> 63) ? u & ~(std::uint64_t{1} << 63) : ~u;
    double k;
    std::memcpy(&k, &u, sizeof k);
    return k;
  }
  static Entry entry(std::uint32_t id, double key) { return {id, scramble(id), encode(key)}; }
  static U128 value(const Entry& e) {
    static_assert(sizeof(Entry) == 16 && offsetof(Entry, tie) == 4 && offsetof(Entry, key) == 8 &&
                  __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__);
    U128 v;
    std::memcpy(&v, &e, sizeof v);  // little-endian: key, then tie, then id
    return v;
  }
  static bool less(const Entry& a, const Entry& b) { return value(a) < value(b); }
  // note: 4-ary: half the levels of a binary heap, and a node's children share a cache line
  // or two. Pops come in the same order (keys and ties are totally ordered).
  // note: not aligned to cache lines (children in one line): 0.6 % fewer cycles in qem, but
  // its aligned allocations raised dpts-par's peak memory on San Gabriel from 104 to 119 MB.
  static constexpr std::size_t kArity = 4;
  const Entry& at(std::size_t i) const { return heap_[i]; }
  void place(std::size_t i, const Entry& e) {
    heap_[i] = e;
    pos_[e.id] = static_cast<std::uint32_t>(i);
  }
  // The smallest of the children [first, end) (end > first).
  std::size_t min_child(std::size_t first, std::size_t end) const {
    // 1 if x orders before y, else 0: used as a number, so that the choice compiles to
    // arithmetic, not to a branch mispredicted half the time.
    auto before = [&](std::size_t x, std::size_t y) -> std::size_t {
      return value(at(x)) < value(at(y)) ? 1 : 0;
    };
    // note: a full set of children apart, as a tournament: two pairs, then their winners.
    if (first + kArity <= end) {
      const std::size_t a = first + before(first + 1, first);
      const std::size_t b = first + 2 + before(first + 3, first + 2);
      return a + (b - a) * before(b, a);
    }
    std::size_t child = first;
    for (std::size_t c = first + 1; c < end; ++c) {
      if (before(c, child)) child = c;
    }
    return child;
  }
  // Entry e into the hole at i, moved up past larger parents.
  void sift_up(std::size_t i, const Entry e) {
    while (i > 0) {
      const std::size_t parent = (i - 1) / kArity;
      if (!less(e, at(parent))) break;
      place(i, at(parent));
      i = parent;
    }
    place(i, e);
  }
  // Entry e into the hole at i, moved down past smaller children.
  void sift_down(std::size_t i, const Entry e) {
    const std::size_t n = size();
    for (;;) {
      const std::size_t first = kArity * i + 1;
      if (first >= n) break;
      const std::size_t child = min_child(first, n);
      if (!less(at(child), e)) break;
      place(i, at(child));
      i = child;
    }
    place(i, e);
  }
  // Entry e (the last one, after a pop) into the hole at the top: the hole taken down to a
  // leaf along the smallest children without comparing e, which then moves up (Floyd's
  // bottom-up heapsort step). The same place as sift_down's (the path's children grow
  // downwards), in fewer comparisons: the last entry mostly belongs near the leaves.
  void sift_down_from_top(const Entry e) {
    const std::size_t n = size();
    std::size_t i = 0;
    for (;;) {
      const std::size_t first = kArity * i + 1;
      if (first >= n) break;
      const std::size_t child = min_child(first, n);
      place(i, at(child));
      i = child;
    }
    sift_up(i, e);
  }

  std::vector<std::uint32_t> pos_;
  std::vector<Entry> heap_;
};

}  // namespace dpts::core

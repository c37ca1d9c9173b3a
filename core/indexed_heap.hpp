// A 4-ary min-heap of item ids keyed by (priority, id), with O(log n) update and erase; only
// the entries of the lowest keys in the heap, the rest set aside by key band.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace dpts::core {

// Items are ids in [0, capacity). Equal priorities are ordered by a fixed bijective scramble of
// the id, so the order of pops is fully determined by the keys (deterministic tie-breaking).
// note: scrambling, not the plain id, matters for elimination: on flat ground every vertex ties
// at importance 0, and removing them in row-major order sweeps a front across the DEM whose
// vertices gain thousands of neighbours; a scattered order keeps degrees near 6.
// note: the heap holds only the entries whose keys lie below a bound (a band edge); the others
// wait in bands of keys (four per binary order of magnitude), unordered, and the lowest band
// enters the heap when it runs empty. A pop is still the least (key, tie) of all, so the order
// of pops is the heap's alone, but sifting walks a heap of the current band (a few thousand
// entries, in cache) instead of every queued one (vp on San Gabriel: 770k entries, 12 MB).
class IndexedMinHeap {
 public:
  static constexpr std::uint32_t kAbsent = std::numeric_limits<std::uint32_t>::max();

  explicit IndexedMinHeap(std::size_t capacity = 0)
      : pos_(capacity, kAbsent), band_of_(capacity, 0) {
    if (capacity >= kInBand) throw std::length_error("IndexedMinHeap: capacity too large");
  }

  // note: whenever any entry is queued the heap holds one (refill), so the least is its top.
  bool empty() const { return heap_.empty(); }
  std::size_t size() const { return heap_.size() + banded_; }
  bool contains(std::uint32_t id) const { return pos_[id] != kAbsent; }
  std::uint32_t top() const { return at(0).id(); }
  double top_key() const { return decode(at(0).key); }

  // Builds the heap from (id, key) pairs at once, in O(n) (ids absent).
  void assign(const std::vector<std::uint32_t>& ids, const std::vector<double>& keys) {
    for (std::size_t i = 0; i < ids.size(); ++i) push_unordered(ids[i], keys[i]);
    heapify();
  }

  // Queues (id, key) without ordering (id must be absent); heapify() then orders all at once,
  // in O(n). note: set aside in its band, even below the bound: heapify takes any such in.
  void push_unordered(std::uint32_t id, double key) { to_band(entry(id, key)); }
  void heapify() {
    // Bands below the bound hold only push_unordered's: into the heap, then ordered.
    for (std::uint32_t b = lowest_band(0); b < bound_band_; b = lowest_band(b + 1)) {
      take_band(b);
    }
    order();
    if (heap_.empty()) refill();
  }

  // Hints that id's key will be set soon: its slot (prefetch_slot), then, once that is at
  // hand, its entry and the entry's parent (prefetch), asked for from memory ahead of time.
  void prefetch_slot(std::uint32_t id) const { __builtin_prefetch(&pos_[id]); }
  void prefetch(std::uint32_t id) const {
    const std::uint32_t p = pos_[id];
    if (p >= kInBand) return;  // absent, or in a band
    __builtin_prefetch(&heap_[p]);
    if (p > 0) __builtin_prefetch(&heap_[(p - 1) / kArity]);
  }

  // Inserts id or changes its key.
  void set(std::uint32_t id, double key) {
    const std::uint32_t p = pos_[id];
    const std::uint64_t k = encode(key);
    if (p < kInBand) {  // in the heap: moved there, or out to its band
      Entry e = at(p);
      e.key = k;
      if (band(k) < bound_band_) {
        if (less(e, at(p))) {
          sift_up(p, e);
        } else {
          sift_down(p, e);
        }
        return;
      }
      remove_at(p);
      queue(e);
      return;
    }
    if (p != kAbsent) {  // in a band: changed there, or moved
      const std::uint32_t old = band_of_[id];
      if (band(k) >= bound_band_ && band(k) == old) {
        band_vec(old)[p - kInBand].key = k;
        return;
      }
      from_band(id);
    }
    queue(make(id, k));
  }

  void erase(std::uint32_t id) {
    const std::uint32_t p = pos_[id];
    if (p == kAbsent) return;
    if (p >= kInBand) {
      from_band(id);
    } else {
      remove_at(p);
      if (heap_.empty()) refill();
    }
    pos_[id] = kAbsent;
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
    for (const auto& b : bands_) {
      for (const Entry& e : b) fn(decode(e.key));
    }
  }
  std::uint32_t pop() {
    const std::uint32_t id = at(0).id();
    pos_[id] = kAbsent;
    const Entry last = heap_.back();
    heap_.pop_back();
    if (!heap_.empty()) {
      sift_down_from_top(last);
    } else {
      refill();
    }
    return id;
  }

 private:
  __extension__ typedef unsigned __int128 U128;  // GCC's and Clang's (no ISO C++ type)
  // note: the key as an unsigned integer of the same order (the double's bits, the sign bit
  // flipped, negatives all flipped; -0 as +0, NaN above +infinity), and the entry laid out so
  // that one unsigned 128-bit comparison orders by (key, tie): sifting chooses among children
  // without branches (the double and tie tests were a third of qem's collapse loop).
  // note: two 64-bit words, the 128-bit value made from them in registers: an entry built
  // field by field (id, tie, key: three stores) and read back as one 16-byte value could not
  // be forwarded from the store buffer, and each such read waited for every older store to
  // reach the cache, cache misses included (perf: half of `set`'s samples, on that read).
  struct Entry {
    std::uint64_t lo;   // tie << 32 | id (ties are unique: the id never decides)
    std::uint64_t key;
    std::uint32_t id() const { return static_cast<std::uint32_t>(lo); }
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
  static Entry make(std::uint32_t id, std::uint64_t key) {
    return {std::uint64_t{scramble(id)} << 32 | id, key};
  }
  static Entry entry(std::uint32_t id, double key) { return make(id, encode(key)); }
  static U128 value(const Entry& e) { return U128{e.key} << 64 | e.lo; }
  static bool less(const Entry& a, const Entry& b) { return value(a) < value(b); }
  // e appended to v word by word, never through a copy in memory (see Entry).
  static void append(std::vector<Entry>& v, const Entry e) {
    v.emplace_back();
    v.back().lo = e.lo;
    v.back().key = e.key;
  }
  // note: 4-ary: half the levels of a binary heap, and a node's children share a cache line
  // or two. Pops come in the same order (keys and ties are totally ordered).
  // note: not aligned to cache lines (children in one line): 0.6 % fewer cycles in qem, but
  // its aligned allocations raised dpts-par's peak memory on San Gabriel from 104 to 119 MB.
  static constexpr std::size_t kArity = 4;
  // The bands: the top 14 bits of the encoded key (its sign, binary exponent and two bits
  // more: four bands an octave).
  // note: vp on San Gabriel to 10 %: the heap held 81k of its 423k queued entries on average
  // with an octave a band, 18k with four; qem's 1.8k and 0.4k of 29k.
  static constexpr int kBandShift = 50;
  static constexpr std::uint32_t kBands = 1u << (64 - kBandShift);
  // pos_ of an id in a band: kInBand + its index there (its band in band_of_).
  static constexpr std::uint32_t kInBand = 0x80000000u;
  static std::uint32_t band(std::uint64_t key) {
    return static_cast<std::uint32_t>(key >> kBandShift);
  }
  // Entry e (its id not queued, or just taken out) set aside in its band.
  void to_band(const Entry e) {
    const std::uint32_t b = band(e.key);
    // note: room for the bands from the lowest to the highest used (a few hundred), not all.
    if (bands_.empty()) {
      band_lo_ = b;
      bands_.resize(1);
    } else if (b < band_lo_) {
      bands_.insert(bands_.begin(), band_lo_ - b, std::vector<Entry>());
      band_lo_ = b;
    } else if (b - band_lo_ >= bands_.size()) {
      bands_.resize(b - band_lo_ + 1);
    }
    auto& v = band_vec(b);
    if (v.empty()) nonempty_[b >> 6] |= std::uint64_t{1} << (b & 63);
    pos_[e.id()] = kInBand + static_cast<std::uint32_t>(v.size());
    band_of_[e.id()] = static_cast<std::uint16_t>(b);
    append(v, e);
    ++banded_;
  }
  // Id's entry taken out of its band (its pos_ left for the caller to set).
  void from_band(std::uint32_t id) {
    const std::uint32_t b = band_of_[id];
    auto& v = band_vec(b);
    const std::uint32_t i = pos_[id] - kInBand;
    if (i + 1 != v.size()) {
      v[i] = v.back();
      pos_[v[i].id()] = kInBand + i;
    }
    v.pop_back();
    if (v.empty()) nonempty_[b >> 6] &= ~(std::uint64_t{1} << (b & 63));
    --banded_;
  }
  // The lowest non-empty band from b on, kBands if none.
  std::uint32_t lowest_band(std::uint32_t b) const {
    while (b < kBands) {
      const std::uint64_t w = nonempty_[b >> 6] >> (b & 63);
      if (w) return b + static_cast<std::uint32_t>(__builtin_ctzll(w));
      b = (b | 63) + 1;
    }
    return kBands;
  }
  // Band b's entries appended to the heap, unordered; the bound raised past b.
  void take_band(std::uint32_t b) {
    auto& v = band_vec(b);
    heap_.reserve(heap_.size() + v.size());
    for (const Entry& e : v) {
      pos_[e.id()] = static_cast<std::uint32_t>(heap_.size());
      heap_.push_back(e);
    }
    banded_ -= v.size();
    std::vector<Entry>().swap(v);
    nonempty_[b >> 6] &= ~(std::uint64_t{1} << (b & 63));
    bound_band_ = std::max(bound_band_, b + 1);
  }
  // The heap (empty) filled with the lowest band, if any is left.
  void refill() {
    if (banded_ == 0) return;
    take_band(lowest_band(bound_band_));
    order();
  }
  // The heap's entries, in any order, made a heap (in O(n)).
  void order() {
    const std::size_t n = heap_.size();
    for (std::size_t i = std::min(n, n / kArity + 1); i-- > 0;) sift_down(i, at(i));
  }
  // Entry e (its id not queued) into the heap below the bound, else into its band; the heap
  // refilled if that left it empty.
  void queue(const Entry e) {
    if (band(e.key) < bound_band_) {
      append(heap_, e);
      sift_up(heap_.size() - 1, e);
    } else {
      to_band(e);
      if (heap_.empty()) refill();
    }
  }
  // The heap's entry at slot p taken out (its pos_ left for the caller to set).
  void remove_at(std::size_t p) {
    const Entry last = heap_.back();
    heap_.pop_back();
    if (p == heap_.size()) return;
    if (p > 0 && less(last, at((p - 1) / kArity))) {
      sift_up(p, last);
    } else {
      sift_down(p, last);
    }
  }
  const Entry& at(std::size_t i) const { return heap_[i]; }
  void place(std::size_t i, const Entry e) {
    heap_[i].lo = e.lo;
    heap_[i].key = e.key;
    pos_[e.id()] = static_cast<std::uint32_t>(i);
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
    const std::size_t n = heap_.size();
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
    const std::size_t n = heap_.size();
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

  std::vector<std::uint32_t> pos_;      // heap slot, kInBand + index in its band, or kAbsent
  std::vector<std::uint16_t> band_of_;  // an id's band, while it is in one
  std::vector<Entry> heap_;
  std::vector<std::vector<Entry>> bands_;  // band band_lo_ + i at i, as far as any was used
  std::uint32_t band_lo_ = 0;
  std::vector<Entry>& band_vec(std::uint32_t b) { return bands_[b - band_lo_]; }
  std::uint64_t nonempty_[kBands / 64] = {};
  std::size_t banded_ = 0;        // entries in the bands
  std::uint32_t bound_band_ = 0;  // keys of lower bands go into the heap
};

}  // namespace dpts::core

// An allocator for large arrays read in no particular order (Dijkstra's labels, the Steiner
// graph's records): backed by transparent huge pages where the kernel offers them.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace dpts::core {

// note: a search over hundreds of megabytes touches a new 4 KiB page at nearly every step, and
// the page walks (TLB misses) cost as much as the cache misses: 2 MiB pages took 12 % off the
// geodesic searches on a 770k-cell DEM. The kernel (Debian's default: THP "madvise") gives them
// only to memory asked for with madvise, before it is first touched, so a std::vector cannot
// get them later. Small arrays, and kernels without THP, get ordinary memory.
template <typename T>
struct HugePageAllocator {
  using value_type = T;
  static constexpr std::size_t kHugePage = std::size_t{2} << 20;

  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) {}

  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_alloc();
    const std::size_t bytes = n * sizeof(T);
    void* p = nullptr;
    if (bytes >= kHugePage) {
      const std::size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
      p = std::aligned_alloc(kHugePage, rounded);
#ifdef __linux__
      if (p) madvise(p, rounded, MADV_HUGEPAGE);  // advice only: a refusal changes nothing
#endif
    } else {
      constexpr std::size_t align =
          alignof(T) > alignof(std::max_align_t) ? alignof(T) : alignof(std::max_align_t);
      p = std::aligned_alloc(align, (bytes + align) / align * align);
    }
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t) { std::free(p); }

  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const {
    return true;
  }
  template <typename U>
  bool operator!=(const HugePageAllocator<U>&) const {
    return false;
  }
};

template <typename T>
using HugeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace dpts::core

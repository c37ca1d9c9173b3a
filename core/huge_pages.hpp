// An allocator for large arrays read in no particular order (Dijkstra's labels, the Steiner
// graph's records): backed by transparent huge pages where the kernel offers them.
#pragma once

#include <cstddef>
#include <cstdint>
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
#ifdef __linux__
    if (bytes >= kHugePage) {
      // note: mapped here, not by malloc: glibc raises its mmap threshold to the size of each
      // mapped block freed (up to 32 MiB), after which arrays of that size come from the
      // threads' arenas and stay there once freed. Each search's labels then took a new place,
      // and the peak grew with every set measured. A mapping goes back to the kernel on free.
      const std::size_t rounded = round_up(bytes);
      void* raw = mmap(nullptr, rounded + kHugePage, PROT_READ | PROT_WRITE,
                       MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
      if (raw == MAP_FAILED) throw std::bad_alloc();
      // the first huge page boundary within the mapping; the rest (before it, and the
      // kHugePage - (aligned - at) > 0 bytes after the block) unmapped
      const auto at = reinterpret_cast<std::uintptr_t>(raw);
      const std::uintptr_t aligned = round_up(at);
      if (aligned > at) munmap(raw, aligned - at);
      munmap(reinterpret_cast<void*>(aligned + rounded), at + kHugePage - aligned);
      madvise(reinterpret_cast<void*>(aligned), rounded, MADV_HUGEPAGE);  // advice only
      return reinterpret_cast<T*>(aligned);
    }
#endif
    constexpr std::size_t align =
        alignof(T) > alignof(std::max_align_t) ? alignof(T) : alignof(std::max_align_t);
    void* p = std::aligned_alloc(align, (bytes + align) / align * align);
    if (!p) throw std::bad_alloc();
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) {
#ifdef __linux__
    if (n * sizeof(T) >= kHugePage) {
      munmap(p, round_up(n * sizeof(T)));
      return;
    }
#endif
    std::free(p);
  }
  static std::size_t round_up(std::size_t bytes) {
    return (bytes + kHugePage - 1) / kHugePage * kHugePage;
  }

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

// This process's memory: resident and peak sizes, what it may still use, and byte counts
// for messages.
#include "parallel/memory.hpp"

#include <malloc.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <optional>
#include <string>

// note: AddressSanitizer and ThreadSanitizer replace malloc: glibc's malloc_trim then walks
// an arena it never set up (SEGV in mtrim, seen under ASan once the qem engine made more
// pieces), and mallopt would tune an allocator nobody uses.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define DPTS_SANITIZED_MALLOC 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define DPTS_SANITIZED_MALLOC 1
#endif
#endif

// The heap on transparent huge pages (keep_freed_memory): glibc 2.33 or later (mallinfo2), on
// Linux.
#if defined(__GLIBC__) && !defined(DPTS_SANITIZED_MALLOC) && defined(__linux__)
#if __GLIBC_PREREQ(2, 33)
#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>
#ifdef MADV_HUGEPAGE
#define DPTS_HUGE_HEAP 1
#endif
#endif
#endif

namespace dpts::par {

namespace {

// Blocks of this size and more are mapped on their own (keep_freed_memory).
[[maybe_unused]] constexpr std::size_t kMapThreshold = std::size_t{32} << 20;

#ifdef DPTS_HUGE_HEAP
constexpr std::size_t kHugePage = std::size_t{2} << 20;
constexpr std::size_t kHugeHeap = std::size_t{256} << 20;  // the heap's part on huge pages
std::atomic<bool> huge_heap{false};        // the heap's next part is advised (keep_freed_memory)
constexpr int kDefaultTopPad = 128 << 10;  // glibc's M_TOP_PAD

// The next kHugeHeap bytes of malloc's heap (its main arena, above the program's data) made
// now and advised for transparent huge pages, before anything touches them (what
// glibc.malloc.hugetlb=1 does, which only the environment sets, before the process starts).
// The heap keeps them free at its top (M_TOP_PAD): a trim hands back only what lies above.
// False, the pad as glibc's default, where the heap could not grow (strict overcommit, a heap
// that is not contiguous): malloc would ask for the pad at every growth.
// From the main thread, before other threads start (malloc serves it from the main arena).
bool reserve_huge_heap() {
  mallopt(M_TOP_PAD, static_cast<int>(kHugeHeap));
  const auto before = reinterpret_cast<std::uintptr_t>(sbrk(0));
  // A block larger than the heap's free top: malloc extends the heap, by the pad more.
  const std::size_t top = mallinfo2().keepcost;
  bool grown = false;
  if (top + kHugePage < kMapThreshold && before != static_cast<std::uintptr_t>(-1)) {
    // note: volatile, or the compiler drops an allocation nothing reads.
    void* volatile block = std::malloc(top + kHugePage);
    std::free(block);
    const auto after = reinterpret_cast<std::uintptr_t>(sbrk(0));
    const std::uintptr_t from = (before + kHugePage - 1) / kHugePage * kHugePage;
    const std::uintptr_t to = after / kHugePage * kHugePage;
    grown = after >= before + kHugeHeap / 2 && to > from;
    if (grown) madvise(reinterpret_cast<void*>(from), to - from, MADV_HUGEPAGE);
  }
  if (!grown) mallopt(M_TOP_PAD, kDefaultTopPad);
  return grown;
}
#endif

}  // namespace

void release_free_memory() {
#if defined(__GLIBC__) && !defined(DPTS_SANITIZED_MALLOC)
  malloc_trim(0);
#endif
#ifdef DPTS_HUGE_HEAP
  // note: the trim handed back the heap's free top, huge pages included; from here on the
  // heap is as glibc makes it. Made again after each trim (a large DEM's groups, the meta
  // method's pieces), the reservation cost time and memory: San Gabriel resampled to 19M
  // cells, 2 threads, peak 348 -> 368-424 MB, 19.3 -> 20.9-21.9 s.
  if (huge_heap.exchange(false)) mallopt(M_TOP_PAD, kDefaultTopPad);
#endif
}

bool huge_page_heap() {
#ifdef DPTS_HUGE_HEAP
  return huge_heap;
#else
  return false;
#endif
}

void keep_freed_memory() {
#if defined(__GLIBC__) && !defined(DPTS_SANITIZED_MALLOC)
  mallopt(M_MMAP_THRESHOLD, static_cast<int>(kMapThreshold));
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
#endif
#ifdef DPTS_HUGE_HEAP
  // note: not under a limit of address space or data (ulimit -v, -d): the heap's free top
  // would take kHugeHeap of it from the start.
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit limit{};
    if (getrlimit(resource, &limit) != 0 || limit.rlim_cur != RLIM_INFINITY) return;
  }
  // note: the main thread's heap alone (each other thread has an arena of its own): one
  // arena for every thread (M_ARENA_MAX=1) put the worker's blocks there too, but its lock
  // cost more (San Gabriel, qem at 2 threads: 0.79 s against 0.71; vp-meta 5 % slower).
  huge_heap = reserve_huge_heap();
#endif
}

namespace {

// A "Name:   123 kB" line of /proc/self/status, in kB; 0 where unknown.
std::size_t status_kb(const char* name) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::size_t n = std::strlen(name);
  while (std::getline(status, line)) {
    if (line.compare(0, n, name) == 0) return std::strtoull(line.c_str() + n, nullptr, 10);
  }
  return 0;
}

}  // namespace

std::size_t peak_rss_kb() { return status_kb("VmHWM:"); }

std::size_t rss_kb() { return status_kb("VmRSS:"); }

namespace {

// The first number in a file (a cgroup limit or usage), or nullopt ("max", missing, unreadable).
std::optional<double> read_number(const char* path) {
  std::ifstream in(path);
  double v = 0;
  if (in >> v) return v;
  return std::nullopt;
}

}  // namespace

std::size_t available_memory_bytes() {
  double avail = std::numeric_limits<double>::infinity();
  std::ifstream meminfo("/proc/meminfo");
  std::string line;
  while (std::getline(meminfo, line)) {
    if (line.rfind("MemAvailable:", 0) == 0) avail = std::strtod(line.c_str() + 13, nullptr) * 1024;
  }
  const auto limit2 = read_number("/sys/fs/cgroup/memory.max");
  const auto usage2 = read_number("/sys/fs/cgroup/memory.current");
  if (limit2 && usage2) avail = std::min(avail, std::max(0.0, *limit2 - *usage2));
  const auto limit1 = read_number("/sys/fs/cgroup/memory/memory.limit_in_bytes");
  const auto usage1 = read_number("/sys/fs/cgroup/memory/memory.usage_in_bytes");
  if (limit1 && usage1 && *limit1 < 1e18) avail = std::min(avail, std::max(0.0, *limit1 - *usage1));
  return std::isfinite(avail) ? static_cast<std::size_t>(avail)
                              : std::numeric_limits<std::size_t>::max();
}

std::string format_bytes(double bytes) {
  char buf[32];
  // Binary units, as --tile-mb and --max-memory count them.
  if (bytes >= 1024.0 * (1 << 20)) {
    std::snprintf(buf, sizeof buf, "%.1f GB", bytes / (1024.0 * (1 << 20)));
  } else {
    std::snprintf(buf, sizeof buf, "%.0f MB", std::ceil(bytes / (1 << 20)));
  }
  return buf;
}

std::size_t worker_threads() {
  return std::min(static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()),
                  tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace dpts::par

// This process's memory: resident and peak sizes, what it may still use, and byte counts
// for messages.
#include "parallel/memory.hpp"

#include <malloc.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <tbb/task_scheduler_observer.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
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

// note: glibc gives each other thread an arena of its own, in heaps of 64 MiB (HEAP_MAX_SIZE on
// 64-bit) aligned to their size, grown page by page as blocks are made: ordinary pages, each
// faulted in on its own (San Gabriel, qem at 2 threads: the worker's first strip of the count
// took 11 ms to read where the main thread took 2, and the count 32-39 ms against 15; with
// glibc.malloc.hugetlb=1 in the environment, 14-18).
constexpr std::size_t kArenaHeap = std::size_t{64} << 20;
// What a worker's heap is grown by at once (freed again at its top, where it stays: the trim
// threshold is 128 MiB): its blocks then come from huge pages, from the start.
constexpr std::size_t kWorkerHeap = std::size_t{24} << 20;

// Whether [from, to) is all mapped, anonymous and private (no file, not the main heap or a
// stack), by /proc/self/maps.
bool anonymous_range(std::uintptr_t from, std::uintptr_t to) {
  std::ifstream maps("/proc/self/maps");
  std::string line;
  std::uintptr_t covered = from;
  while (std::getline(maps, line) && covered < to) {
    unsigned long start = 0, end = 0, inode = 0;
    char perms[8] = {}, dev[16] = {};
    unsigned long long offset = 0;
    int path_at = 0;
    if (std::sscanf(line.c_str(), "%lx-%lx %7s %llx %15s %lu %n", &start, &end, perms, &offset, dev,
                    &inode, &path_at) < 6) {
      return false;
    }
    if (end <= covered) continue;
    if (start > covered) return false;  // a gap
    if (inode != 0 || perms[3] != 'p' ||
        (path_at > 0 && static_cast<std::size_t>(path_at) < line.size())) {
      return false;
    }
    covered = end;
  }
  return covered >= to;
}

// The calling thread's malloc heap (not the main thread's) advised for transparent huge pages
// and grown by kWorkerHeap; its blocks from then on start at the next huge page boundary.
// note: the pages already touched (the arena's own records, at the heap's start) keep their
// huge page's span on ordinary pages: blocks there took 512 faults for 2 MiB. The room up to
// the boundary is held by a block never touched nor freed (address space only).
void advise_thread_heap() {
  void* volatile block = std::malloc(kWorkerHeap);
  if (!block) return;
  const auto at = reinterpret_cast<std::uintptr_t>(block);
  const std::uintptr_t heap = at / kArenaHeap * kArenaHeap;
  const bool advised = anonymous_range(heap, heap + kArenaHeap) &&
                       madvise(reinterpret_cast<void*>(heap), kArenaHeap, MADV_HUGEPAGE) == 0;
  std::free(block);
  if (!advised) return;
  const std::uintptr_t boundary = (at + kHugePage - 1) / kHugePage * kHugePage;
  if (boundary - at > 4 * sizeof(void*)) {
    // note: short of the boundary by the next block's header and malloc's rounding; volatile,
    // or the compiler drops an allocation nothing reads.
    void* volatile hold = std::malloc(boundary - at - 4 * sizeof(void*));
    static_cast<void>(hold);
  }
}

// Each worker thread's heap on huge pages (advise_thread_heap) as it first runs a task of the
// main thread's arena, while the main heap is (huge_heap).
class WorkerHeaps : public tbb::task_scheduler_observer {
 public:
  WorkerHeaps() { observe(true); }
  void on_scheduler_entry(bool is_worker) override {
    thread_local bool advised = false;
    if (!is_worker || advised || !huge_heap) return;
    advised = true;
    advise_thread_heap();
  }
};
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
  // note: made once and never destroyed (so never unhooked while TBB shuts down at exit).
  static WorkerHeaps* workers = nullptr;
  if (huge_heap && !workers) workers = new WorkerHeaps;
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

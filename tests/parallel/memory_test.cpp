// The executables' heap (keep_freed_memory): blocks come on transparent huge pages where the
// kernel offers them, the main thread's and oneTBB's workers', until the first trim.
#include "parallel/memory.hpp"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace {

// A "Name:   123 kB" line of the file, in kB; -1 where there is none.
long kb_line(const char* path, const std::string& name) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, name.size(), name) == 0)
      return std::strtol(line.c_str() + name.size(), nullptr, 10);
  }
  return -1;
}

// The kernel's transparent huge page setting, e.g. "always [madvise] never"; empty if none.
std::string thp_setting() {
  std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  std::getline(in, line);
  return line;
}

}  // namespace

TEST_CASE("keep_freed_memory: the heap's blocks on huge pages, where the kernel offers them") {
  dpts::par::keep_freed_memory();
  const std::string thp = thp_setting();
  const long before = kb_line("/proc/self/smaps_rollup", "AnonHugePages:");
  if (!dpts::par::huge_page_heap() || thp.empty() || thp.find("[never]") != std::string::npos ||
      before < 0) {
    WARN("no huge pages here (sanitizers, or the kernel's setting: '" << thp << "')");
    return;
  }
  // 24 MiB: below malloc's mapping threshold (32 MiB), so from the heap; every page touched.
  constexpr std::size_t kBytes = std::size_t{24} << 20;
  std::vector<char> block(kBytes);
  std::memset(block.data(), 1, block.size());
  const long after = kb_line("/proc/self/smaps_rollup", "AnonHugePages:");
  INFO("AnonHugePages " << before << " kB -> " << after << " kB; THP " << thp);
  // note: the block starts anywhere in a huge page; at least 10 of the 12 it spans are whole.
  CHECK(after - before >= 10 * 2048);
  CHECK(block[kBytes - 1] == 1);
  // A trim hands the heap's top back: from then on, the heap is glibc's own.
  dpts::par::release_free_memory();
  CHECK_FALSE(dpts::par::huge_page_heap());
}

TEST_CASE("keep_freed_memory: a worker thread's blocks on huge pages too") {
  dpts::par::keep_freed_memory();
  const std::string thp = thp_setting();
  if (!dpts::par::huge_page_heap() || thp.empty() || thp.find("[never]") != std::string::npos ||
      kb_line("/proc/self/smaps_rollup", "AnonHugePages:") < 0) {
    WARN("no huge pages here (sanitizers, or the kernel's setting: '" << thp << "')");
    return;
  }
  // A block made and touched by a worker thread (not the main one, whose heap the case above
  // checks), while the main thread waits: 8 MiB, at least 3 whole huge pages.
  constexpr std::size_t kBytes = std::size_t{8} << 20;
  tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
  std::atomic<long> grown{-1};
  std::atomic<bool> done{false};
  tbb::parallel_for(0, 64, [&](int) {
    if (tbb::this_task_arena::current_thread_index() == 0) {
      while (!done) std::this_thread::yield();  // the main thread: out of the way
      return;
    }
    if (done.exchange(true)) return;
    const long before = kb_line("/proc/self/smaps_rollup", "AnonHugePages:");
    std::vector<char> block(kBytes);
    std::memset(block.data(), 1, block.size());
    grown = kb_line("/proc/self/smaps_rollup", "AnonHugePages:") - before + (block[7] - 1);
  });
  if (grown < 0) {
    WARN("no worker thread ran a task here (one core?)");
    return;
  }
  INFO("AnonHugePages grew by " << grown << " kB in the worker; THP " << thp);
  CHECK(grown >= 3 * 2048);
}

// The executables' heap (keep_freed_memory): blocks come on transparent huge pages where the
// kernel offers them, until the first trim.
#include "parallel/memory.hpp"

#include <catch2/catch.hpp>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
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

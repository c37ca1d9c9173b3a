// This process's memory, as the engines and tools check and report it (Linux /proc and
// cgroups).
#pragma once

#include <cstddef>
#include <string>

namespace dpts::par {

// Peak resident memory of this process so far in kB (Linux VmHWM), 0 where unknown.
std::size_t peak_rss_kb();
// Resident memory of this process now in kB (Linux VmRSS), 0 where unknown.
std::size_t rss_kb();

// Memory this process may still use, in bytes: the system's MemAvailable, or less when a
// cgroup (v2 memory.max, v1 limit_in_bytes) limits it; SIZE_MAX where unknown.
std::size_t available_memory_bytes();

// "12.3 GB" / "456 MB": a byte count for messages.
std::string format_bytes(double bytes);

// The threads that may run this task arena's tasks at once: its own concurrency, bounded by a
// tbb::global_control where one is active (dpts-par's and dpts-eval's --threads). What the
// memory estimates count one working set per.
std::size_t worker_threads();

}  // namespace dpts::par

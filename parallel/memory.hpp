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

// Hands memory freed by a finished piece back to the system. glibc keeps freed heap memory
// (a piece's triangulation is freed in thousands of blocks) for reuse; as kept-vertex outputs
// accumulate between pieces, that retained memory fragments and the process grows with the
// DEM although no more is live. Trimming between pieces (or groups of them) keeps the
// footprint flat. Not under AddressSanitizer or ThreadSanitizer (memory.cpp).
void release_free_memory();

// Asks malloc (glibc's) to keep freed blocks for reuse, not hand them back to the system and
// fault them in again, where it would by default: blocks of up to 32 MiB come from its heap
// from the start (by default from the second of a size on: until one is freed, each is mapped
// on its own and unmapped when freed), and free memory at the top of the heap is kept up to
// 128 MiB. release_free_memory still hands everything free back. For executables, before their
// threads start.
// Also advises the next 256 MiB of the main thread's heap (glibc's main arena) for transparent
// huge pages before anything touches them, and the heap of each oneTBB worker thread (its own
// arena) as it first runs a task of the main thread's arena, until the first
// release_free_memory (Linux, with no limit of address space or data; the rest of the heap,
// other arenas and blocks mapped on their own get ordinary pages).
// note: a page the system hands this process costs about 11 us to fault in on these machines
// (a virtual machine), more than the work done on it: San Gabriel to 10 % (qem, 1 thread)
// faulted in 28k pages, 0.21-0.28 s of system time (15 % of the CPU); 17.8k after round 11,
// 3.0-3.2k on huge pages (2.2k of them the loader's, before main).
void keep_freed_memory();

// Whether keep_freed_memory advised the heap for huge pages and no release_free_memory has
// ended it since (never under the sanitizers, off Linux, or under ulimit -v or -d; the kernel
// may still decline them: its transparent_hugepage setting "never").
bool huge_page_heap();

// "12.3 GB" / "456 MB": a byte count for messages.
std::string format_bytes(double bytes);

// The threads that may run this task arena's tasks at once: its own concurrency, bounded by a
// tbb::global_control where one is active (dpts-par's and dpts-eval's --threads). What the
// memory estimates count one working set per.
std::size_t worker_threads();

}  // namespace dpts::par

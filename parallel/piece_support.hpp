// What the piece engines (meta.cpp, qem_engine.cpp) share: stage clocks, progress from
// concurrent pieces, and handing a finished piece's memory back.
#pragma once

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <atomic>
#include <chrono>
#include <mutex>
#include <string_view>
#include <vector>

#include "core/elimination.hpp"
#include "core/errors.hpp"
#include "core/raster_source.hpp"

namespace dpts::par {

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Reads a piece's window and sets read_s to the time it took (waiting for the source
// included: pieces read concurrently).
inline core::HeightGrid read_window(const core::RasterSource& dem, int col0, int row0, int width,
                                    int height, double& read_s) {
  const auto t0 = std::chrono::steady_clock::now();
  core::HeightGrid grid = dem.read(col0, row0, width, height);
  read_s = seconds_since(t0);
  return grid;
}

// Hands memory freed by a finished piece back to the system. glibc keeps freed heap memory
// (a piece's triangulation is freed in thousands of blocks) for reuse; as kept-vertex outputs
// accumulate between pieces, that retained memory fragments and the process grows with the
// DEM although no more is live. Trimming after each piece keeps the footprint flat.
// note: not under AddressSanitizer or ThreadSanitizer: they replace malloc, and glibc's
// malloc_trim then walks an arena it never set up (SEGV in mtrim, seen under ASan once the qem
// engine made more pieces).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define DPTS_SANITIZED_MALLOC 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define DPTS_SANITIZED_MALLOC 1
#endif
#endif
inline void release_free_memory() {
#if defined(__GLIBC__) && !defined(DPTS_SANITIZED_MALLOC)
  malloc_trim(0);
#endif
}

// Progress from concurrent tasks, serialized; remembers a refusal so every task stops.
class SharedProgress {
 public:
  SharedProgress(const core::Progress& progress, std::size_t parts)
      : progress_(progress), partial_(parts, 0.0) {}
  // Reports part i at fraction f of its work; false once the run is to stop.
  bool update(std::size_t i, double f, std::string_view stage) {
    if (stop_) return false;
    std::lock_guard<std::mutex> hold(lock_);
    sum_ += f - partial_[i];
    partial_[i] = f;
    if (progress_ && !progress_(sum_ / static_cast<double>(partial_.size()), stage)) stop_ = true;
    return !stop_;
  }
  void check() const {
    if (stop_) throw Cancelled();
  }

 private:
  const core::Progress& progress_;
  std::vector<double> partial_;
  double sum_ = 0;
  std::mutex lock_;
  std::atomic<bool> stop_{false};
};

}  // namespace dpts::par

// What the piece engines (meta.cpp, qem_engine.cpp) share: stage clocks, progress from
// concurrent pieces, and handing a finished piece's memory back.
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string_view>
#include <vector>

#include "core/elimination.hpp"
#include "core/errors.hpp"
#include "core/raster_source.hpp"
#include "parallel/memory.hpp"

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

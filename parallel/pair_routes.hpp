// Each pair's path seen from above, as the search on one mesh found it, for the search of the
// same points on another mesh to try too (shorten_along); kept within a memory allowance.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/geodesic_path.hpp"

namespace dpts::par {

// The routes of the pairs a < b of K points: each a path's bends and taut points
// (core::PathRoute), from a to b, then b, as float offsets from origin() (8 bytes a point).
// A route is stored once (add) and then given to its pair (assign), so that a search may keep
// several candidates and give each pair the best. They grow with the square of the points
// (a set of 100 points on a 770k-cell DEM's grid TIN stores about 11 MB, every candidate
// counted, about 2.2 KB a pair): those past the memory allowance are
// moved to an unnamed temporary file (in TMPDIR, else /tmp; unlinked at once, its space given
// back however the process ends) and read back from there. Where that file cannot be made or
// written, they stay in memory.
class PairRoutes {
 public:
  using Id = std::uint64_t;
  static constexpr Id kNone = ~Id{0};
  // The memory a store keeps its routes in by default.
  static constexpr std::size_t kDefaultMemory = std::size_t{8} << 20;

  // Routes for 0 points; at most memory_bytes of them in memory (their pairs' index apart).
  explicit PairRoutes(std::size_t memory_bytes = kDefaultMemory);
  ~PairRoutes();
  PairRoutes(PairRoutes&&) noexcept;
  PairRoutes& operator=(PairRoutes&&) noexcept;

  // Drops every route: K points, none with a route, offsets from origin.
  void reset(std::size_t k, const std::array<double, 2>& origin);
  std::size_t points() const { return k_; }
  const std::array<double, 2>& origin() const { return origin_; }

  // Stores the route of the path from point i to point j (route, from i to j) as pair
  // min(i, j) < max(i, j) keeps it (from the lower to the higher point, then end_xy: that
  // point seen from above); returns its id. Safe to call from several threads at once.
  Id add(const core::PathRoute& route, bool reversed, const std::array<double, 2>& end_xy);
  // Gives pair a < b the route `id` (kNone: none). Not at once with itself for one pair.
  void assign(std::size_t a, std::size_t b, Id id) { index_[a * k_ + b] = id; }
  // Pair a < b's route, in the meshes' coordinates, into bends and taut; false (both empty)
  // where it has none. Not at once with add(); at once with itself from several threads.
  bool get(std::size_t a, std::size_t b, std::vector<std::array<double, 2>>& bends,
           std::vector<std::array<double, 2>>& taut) const;

  // Bytes of routes held in memory now, and moved to the file.
  std::size_t memory_bytes() const;
  std::size_t spilled_bytes() const;

 private:
  struct Log;  // the routes' bytes: in memory, then in the file
  std::unique_ptr<Log> log_;
  std::size_t k_ = 0;
  std::array<double, 2> origin_{};
  std::vector<Id> index_;  // pair a < b at a * K + b
};

}  // namespace dpts::par

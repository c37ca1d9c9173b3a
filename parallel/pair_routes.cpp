// PairRoutes: an append-only log of routes, in memory up to an allowance, then in an unnamed
// temporary file.
#include "parallel/pair_routes.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <mutex>
#include <string>

#include "core/errors.hpp"
#include "core/temp_file.hpp"

namespace dpts::par {
namespace {

// A record: its bends' and taut points' counts (two 32-bit words), then their points.
constexpr std::size_t kHeader = 2 * sizeof(std::uint32_t);
using Float2 = std::array<float, 2>;

}  // namespace

struct PairRoutes::Log {
  explicit Log(std::size_t cap) : cap(cap) {}
  ~Log() {
    if (fd >= 0) ::close(fd);
  }
  Log(const Log&) = delete;
  Log& operator=(const Log&) = delete;

  // Moves buf into the file after its first `base` bytes; false (buf kept, and from then on
  // every route) where the file cannot be made or written.
  bool spill() {
    if (no_file) return false;
    if (fd < 0) fd = core::unnamed_temp_file(dir, "dpts-routes");
    std::size_t done = 0;
    while (fd >= 0 && done < buf.size()) {
      const ssize_t n =
          ::pwrite(fd, buf.data() + done, buf.size() - done, static_cast<off_t>(base + done));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    if (fd < 0 || done < buf.size()) {
      no_file = true;
      return false;
    }
    base += buf.size();
    buf.clear();
    return true;
  }

  std::size_t cap;
  std::string dir = core::temp_dir();
  std::mutex m;
  std::vector<char> buf;   // the log's bytes from offset `base` on
  std::uint64_t base = 0;  // the bytes before are in the file
  int fd = -1;
  bool no_file = false;
};

PairRoutes::PairRoutes(std::size_t memory_bytes) : log_(std::make_unique<Log>(memory_bytes)) {}
PairRoutes::~PairRoutes() = default;
PairRoutes::PairRoutes(PairRoutes&&) noexcept = default;
PairRoutes& PairRoutes::operator=(PairRoutes&&) noexcept = default;

void PairRoutes::reset(std::size_t k, const std::array<double, 2>& origin) {
  const std::size_t cap = log_ ? log_->cap : kDefaultMemory;
  log_ = std::make_unique<Log>(cap);
  k_ = k;
  origin_ = origin;
  index_.assign(k * k, kNone);
}

PairRoutes::Id PairRoutes::add(const core::PathRoute& route, bool reversed,
                               const std::array<double, 2>& end_xy) {
  const auto nb = static_cast<std::uint32_t>(route.bends.size() + 1);
  const auto nt = static_cast<std::uint32_t>(route.taut.size() + 1);
  const std::size_t bytes = kHeader + (nb + nt) * sizeof(Float2);
  std::lock_guard<std::mutex> lock(log_->m);
  std::vector<char>& buf = log_->buf;
  if (!buf.empty() && buf.size() + bytes > log_->cap) log_->spill();
  const Id id = log_->base + buf.size();
  std::size_t at = buf.size();
  // note: grown by doubling, but never past the allowance (or the one record beyond it).
  if (at + bytes > buf.capacity()) {
    buf.reserve(std::max(at + bytes, std::min(2 * buf.capacity(), log_->cap)));
  }
  buf.resize(at + bytes);
  std::memcpy(buf.data() + at, &nb, sizeof nb);
  std::memcpy(buf.data() + at + sizeof nb, &nt, sizeof nt);
  at += kHeader;
  auto put = [&](const std::vector<std::array<double, 2>>& from) {
    const std::size_t n = from.size();
    for (std::size_t i = 0; i < n; ++i) {
      const auto& p = from[reversed ? n - 1 - i : i];
      const Float2 f{static_cast<float>(p[0] - origin_[0]), static_cast<float>(p[1] - origin_[1])};
      std::memcpy(buf.data() + at, &f, sizeof f);
      at += sizeof f;
    }
    const Float2 e{static_cast<float>(end_xy[0] - origin_[0]),
                   static_cast<float>(end_xy[1] - origin_[1])};
    std::memcpy(buf.data() + at, &e, sizeof e);
    at += sizeof e;
  };
  put(route.bends);
  put(route.taut);
  return id;
}

bool PairRoutes::get(std::size_t a, std::size_t b, std::vector<std::array<double, 2>>& bends,
                     std::vector<std::array<double, 2>>& taut) const {
  bends.clear();
  taut.clear();
  if (a >= k_ || b >= k_) return false;
  const Id id = index_[a * k_ + b];
  if (id == kNone) return false;
  std::uint32_t n[2];
  std::vector<Float2> spilled;
  const char* points = nullptr;
  if (id >= log_->base) {
    const char* at = log_->buf.data() + (id - log_->base);
    std::memcpy(n, at, sizeof n);
    points = at + kHeader;
  } else {
    auto read = [&](void* to, std::size_t bytes, std::uint64_t from) {
      std::size_t done = 0;
      while (done < bytes) {
        const ssize_t r = ::pread(log_->fd, static_cast<char*>(to) + done, bytes - done,
                                  static_cast<off_t>(from + done));
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) {
          throw IoError("temporary file in " + log_->dir + ": read failed (" +
                        (r < 0 ? std::strerror(errno) : "end of file") + ")");
        }
        done += static_cast<std::size_t>(r);
      }
    };
    read(n, sizeof n, id);
    spilled.resize(n[0] + n[1]);
    read(spilled.data(), spilled.size() * sizeof(Float2), id + kHeader);
    points = reinterpret_cast<const char*>(spilled.data());
  }
  auto take = [&](std::uint32_t count, std::vector<std::array<double, 2>>& to) {
    to.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
      Float2 f;
      std::memcpy(&f, points, sizeof f);
      points += sizeof f;
      to[i] = {origin_[0] + f[0], origin_[1] + f[1]};
    }
  };
  take(n[0], bends);
  take(n[1], taut);
  return true;
}

std::size_t PairRoutes::memory_bytes() const { return log_ ? log_->buf.capacity() : 0; }
std::size_t PairRoutes::spilled_bytes() const { return log_ ? log_->base : 0; }

}  // namespace dpts::par

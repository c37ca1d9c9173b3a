// Buffered output helpers shared by the mesh writers (PLY, OBJ, STL): numbers as text or as
// little-endian bytes into a buffer, flushed to a stream in chunks.
#pragma once

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <string>

#include "core/errors.hpp"

namespace dpts::io::bytes {

// Flush the buffer once it holds this much.
constexpr std::size_t kChunk = 1 << 20;

inline bool host_is_little_endian() {
  const std::uint16_t probe = 1;
  unsigned char first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 1;
}

template <typename T>
void put_le(std::string& buf, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (!host_is_little_endian()) std::reverse(raw, raw + sizeof(T));
  buf.append(raw, sizeof(T));
}

// Shortest round-trip text (std::to_chars: no locale).
template <typename T>
void put_number(std::string& buf, T v) {
  char tmp[32];
  const auto res = std::to_chars(tmp, tmp + sizeof tmp, v);
  buf.append(tmp, res.ptr);
}

// "a b c\n" (a vertex's x y z, a face's indices) in shortest round-trip text.
template <typename T>
void put_xyz_line(std::string& buf, const T* xyz) {
  put_number(buf, xyz[0]);
  buf += ' ';
  put_number(buf, xyz[1]);
  buf += ' ';
  put_number(buf, xyz[2]);
  buf += '\n';
}

// "write failed (why)": errno still holds the failed write's reason (EFBIG, ENOSPC, EIO...).
inline std::string write_failure() {
  const int err = errno;
  return std::string("write failed") + (err ? std::string(" (") + std::strerror(err) + ")" : "");
}

inline void flush(std::ostream& out, std::string& buf) {
  out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  if (!out) throw IoError(write_failure());
  buf.clear();
}

}  // namespace dpts::io::bytes

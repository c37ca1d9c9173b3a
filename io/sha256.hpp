// SHA-256 (FIPS 180-4) of bytes and files: run reports name their outputs by content.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace dpts::io {

class Sha256 {
 public:
  Sha256();
  void update(const void* data, std::size_t size);
  std::string hex();  // finishes the digest: lowercase hex, 64 characters

 private:
  void block(const std::uint8_t* p);
  std::array<std::uint32_t, 8> h_;
  std::array<std::uint8_t, 64> buf_{};
  std::size_t used_ = 0;
  std::uint64_t bytes_ = 0;
};

std::string sha256_hex(const std::string& data);

// SHA-256 of a file's bytes. Throws IoError naming the file if it cannot be read.
std::string sha256_file(const std::string& path);

}  // namespace dpts::io

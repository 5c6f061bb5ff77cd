#pragma once
// SHA-256 (FIPS 180-4), used to record the content hash of every input
// artifact in an output's provenance.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace msfab {

// Incremental hasher: feed bytes with update(), then call hex() or digest()
// once. Reusing a finished hasher is a bug and throws std::logic_error.
class Sha256 {
 public:
  Sha256();
  void update(const void* data, std::size_t size);
  void update(std::string_view data) { update(data.data(), data.size()); }
  std::array<std::uint8_t, 32> digest();
  std::string hex();  // 64 lowercase hex digits

 private:
  void compress(const std::uint8_t* block);

  std::array<std::uint32_t, 8> state_;
  std::array<std::uint8_t, 64> buffer_;
  std::size_t buffered_ = 0;
  std::uint64_t total_bytes_ = 0;
  bool finished_ = false;
};

// Hash of an in-memory byte string.
std::string sha256_hex(std::string_view data);

// Hash of a file's content, read in blocks so files of any size are fine.
// Throws InputError "<path>: no such file" / "<path>: cannot read ...".
// (A separate name from sha256_hex so a path string is never hashed by
// mistake as data.)
std::string sha256_file_hex(const std::string& path);

}  // namespace msfab

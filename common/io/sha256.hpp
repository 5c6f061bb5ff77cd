#pragma once
// SHA-256 (FIPS 180-4), used to record the content hash of every input
// artifact in an output's provenance. The digest is OpenSSL's libcrypto
// (EVP interface); this header keeps libcrypto out of its includers.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

struct evp_md_ctx_st;  // OpenSSL's EVP_MD_CTX

namespace msfab {

// Incremental hasher: feed bytes with update(), then call hex() or digest()
// once. Reusing a finished hasher is a bug and throws std::logic_error.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void update(const void* data, std::size_t size);
  void update(std::string_view data) { update(data.data(), data.size()); }
  std::array<std::uint8_t, 32> digest();
  std::string hex();  // 64 lowercase hex digits

 private:
  struct FreeContext {
    void operator()(evp_md_ctx_st* context) const;
  };
  std::unique_ptr<evp_md_ctx_st, FreeContext> context_;
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

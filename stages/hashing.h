// Content hashing for resumability and provenance: a streaming 128-bit XXH3
// hasher with typed feeds, printed as 32 hex digits. Deterministic across
// machines for the same byte sequence (fixed-width little-endian feeds).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace cellbake {

class Hasher {
 public:
  Hasher();
  ~Hasher();
  Hasher(const Hasher&) = delete;
  Hasher& operator=(const Hasher&) = delete;

  Hasher& bytes(const void* data, std::size_t size);
  Hasher& text(std::string_view s);  // length-prefixed, so "ab"+"c" != "a"+"bc"
  Hasher& u64(std::uint64_t v);
  Hasher& f64(double v);              // by bit pattern (+0 and -0 differ)
  std::string hex() const;            // 32 lowercase hex digits
  std::uint64_t low64() const;

 private:
  void* state_;
};

// Hashes a whole byte buffer; 32 hex digits.
std::string hash_hex(const void* data, std::size_t size);

}  // namespace cellbake

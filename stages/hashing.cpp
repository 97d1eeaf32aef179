#include "stages/hashing.h"

#include <xxhash.h>

#include <cstdio>
#include <cstring>

namespace cellbake {

Hasher::Hasher() : state_(XXH3_createState()) { XXH3_128bits_reset(static_cast<XXH3_state_t*>(state_)); }
Hasher::~Hasher() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

Hasher& Hasher::bytes(const void* data, std::size_t size) {
  XXH3_128bits_update(static_cast<XXH3_state_t*>(state_), data, size);
  return *this;
}
Hasher& Hasher::text(std::string_view s) {
  u64(s.size());
  return bytes(s.data(), s.size());
}
Hasher& Hasher::u64(std::uint64_t v) {
  unsigned char b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
  return bytes(b, 8);
}
Hasher& Hasher::f64(double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, 8);
  return u64(bits);
}
std::string Hasher::hex() const {
  XXH128_hash_t h = XXH3_128bits_digest(static_cast<XXH3_state_t*>(state_));
  char buf[33];
  std::snprintf(buf, sizeof buf, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                static_cast<unsigned long long>(h.low64));
  return buf;
}
std::uint64_t Hasher::low64() const { return XXH3_128bits_digest(static_cast<XXH3_state_t*>(state_)).low64; }

std::string hash_hex(const void* data, std::size_t size) {
  Hasher h;
  h.bytes(data, size);
  return h.hex();
}

}  // namespace cellbake

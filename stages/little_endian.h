// Little-endian fields of the blobs we write (face meshes, grid meshes),
// byte by byte so that the host's endianness and alignment do not matter.
#pragma once

#include <cstdint>
#include <cstring>

namespace cellbake::little_endian {

inline void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline std::uint32_t get_u32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= std::uint32_t{p[i]} << (8 * i);
  return v;
}
inline void put_f32(std::uint8_t* p, float f) {
  std::uint32_t v;
  std::memcpy(&v, &f, 4);
  put_u32(p, v);
}
inline float get_f32(const std::uint8_t* p) {
  const std::uint32_t v = get_u32(p);
  float f;
  std::memcpy(&f, &v, 4);
  return f;
}
inline void put_f64(std::uint8_t* p, double d) {
  std::uint64_t v;
  std::memcpy(&v, &d, 8);
  put_u32(p, static_cast<std::uint32_t>(v));
  put_u32(p + 4, static_cast<std::uint32_t>(v >> 32));
}
inline double get_f64(const std::uint8_t* p) {
  const std::uint64_t v = get_u32(p) | (std::uint64_t{get_u32(p + 4)} << 32);
  double d;
  std::memcpy(&d, &v, 8);
  return d;
}

}  // namespace cellbake::little_endian

// The header of a Stanford PLY file: format, and the elements with their
// scalar and list properties in file order. Reference: Greg Turk, "The PLY
// Polygon File Format" (1994).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "pipeline/readers/buffered_input.h"

namespace cellbake {

enum class PlyType : std::uint8_t { int8, uint8, int16, uint16, int32, uint32, float32, float64 };
enum class PlyFormat : std::uint8_t { ascii, binary_little_endian, binary_big_endian };

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;  // the scalar type, or the item type of a list
  bool is_list = false;
  PlyType count_type = PlyType::uint8;  // lists only
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t line = 0;  // of its "element" line in the header
  std::vector<PlyProperty> properties;
  bool has_lists() const;
  // Bytes of one binary record; meaningful only when !has_lists().
  std::size_t record_size() const;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::ascii;
  std::vector<PlyElement> elements;
  // " line N: ..." for header lines read as comments: an unknown keyword (old
  // exporters wrote e.g. "Created by Blender3D 247" without "comment").
  std::vector<std::string> warnings;
};

// Size in bytes of one binary value of `type`.
inline std::size_t ply_type_size(PlyType type) {
  constexpr std::size_t sizes[] = {1, 1, 2, 2, 4, 4, 4, 8};
  return sizes[static_cast<int>(type)];
}
inline bool ply_type_is_float(PlyType type) { return type == PlyType::float32 || type == PlyType::float64; }

// Reads the header lines of `in` through "end_header", leaving `in` at the
// first byte of the body. A line with an unknown keyword is read as a comment
// (it cannot change the body's layout) and noted in PlyHeader::warnings.
// Throws InputError (file and line) when the magic, format, an
// element/property line or the end_header line is missing or malformed.
PlyHeader read_ply_header(BufferedInput& in);

}  // namespace cellbake

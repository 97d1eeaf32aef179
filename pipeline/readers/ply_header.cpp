#include "pipeline/readers/ply_header.h"

#include <optional>

#include "pipeline/input_error.h"
#include "pipeline/readers/text_scan.h"

namespace cellbake {
namespace {

std::optional<PlyType> parse_type(std::string_view name) {
  if (name == "char" || name == "int8") return PlyType::int8;
  if (name == "uchar" || name == "uint8") return PlyType::uint8;
  if (name == "short" || name == "int16") return PlyType::int16;
  if (name == "ushort" || name == "uint16") return PlyType::uint16;
  if (name == "int" || name == "int32") return PlyType::int32;
  if (name == "uint" || name == "uint32") return PlyType::uint32;
  if (name == "float" || name == "float32") return PlyType::float32;
  if (name == "double" || name == "float64") return PlyType::float64;
  return std::nullopt;
}

}  // namespace

bool PlyElement::has_lists() const {
  for (const PlyProperty& property : properties)
    if (property.is_list) return true;
  return false;
}

std::size_t PlyElement::record_size() const {
  std::size_t size = 0;
  for (const PlyProperty& property : properties) size += ply_type_size(property.type);
  return size;
}

PlyHeader read_ply_header(BufferedInput& in) {
  const auto fail = [&](const std::string& what) {
    throw InputError(in.name(), at_line(in.line_number()), "malformed PLY header: " + what);
  };
  std::string_view line;
  if (!in.next_line(line) || line != "ply") {
    if (in.line_number() == 0) throw InputError(in.name(), "", "empty file, expected a PLY header");
    fail("first line is not 'ply'");
  }
  PlyHeader header;
  bool have_format = false;
  while (in.next_line(line)) {
    TextScan scan(line);
    const std::string_view key = scan.token();
    if (key.empty() || key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      if (!have_format) fail("no 'format' line before end_header");
      return header;
    }
    if (key == "format") {
      const std::string_view format = scan.token();
      if (format == "ascii") {
        header.format = PlyFormat::ascii;
      } else if (format == "binary_little_endian") {
        header.format = PlyFormat::binary_little_endian;
      } else if (format == "binary_big_endian") {
        header.format = PlyFormat::binary_big_endian;
      } else {
        fail("unknown format '" + std::string(format) + "'");
      }
      if (scan.token() != "1.0") fail("unsupported version (expected 1.0)");
      have_format = true;
    } else if (key == "element") {
      PlyElement element;
      element.name = std::string(scan.token());
      std::int64_t count = 0;
      if (element.name.empty() || !scan.integer(count) || count < 0 || !scan.at_end())
        fail("expected 'element <name> <count>'");
      element.count = static_cast<std::uint64_t>(count);
      element.line = in.line_number();
      header.elements.push_back(std::move(element));
    } else if (key == "property") {
      if (header.elements.empty()) fail("property before any element");
      PlyProperty property;
      std::string_view type_name = scan.token();
      if (type_name == "list") {
        property.is_list = true;
        const auto count_type = parse_type(scan.token());
        if (!count_type || ply_type_is_float(*count_type)) fail("list count type must be an integer type");
        property.count_type = *count_type;
        type_name = scan.token();
      }
      const auto type = parse_type(type_name);
      if (!type) fail("unknown property type '" + std::string(type_name) + "'");
      property.type = *type;
      property.name = std::string(scan.token());
      if (property.name.empty() || !scan.at_end()) fail("expected 'property <type> <name>'");
      header.elements.back().properties.push_back(std::move(property));
    } else {
      const std::string text(line.substr(0, 60));
      header.warnings.push_back(" " + at_line(in.line_number()) + ": header line '" + text +
                                (line.size() > 60 ? "...'" : "'") + " has no PLY keyword: read as a comment");
    }
  }
  throw InputError(in.name(), at_line(in.line_number()), "malformed PLY header: no end_header line");
}

}  // namespace cellbake

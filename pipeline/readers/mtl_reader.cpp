#include "pipeline/readers/mtl_reader.h"

#include <algorithm>
#include <memory>

#include "pipeline/input_error.h"
#include "pipeline/readers/buffered_input.h"
#include "pipeline/readers/colour_math.h"
#include "pipeline/readers/contained_paths.h"
#include "pipeline/readers/text_scan.h"

namespace cellbake {
namespace {

// The path operand of a "map_Kd [-options ...] path" line: the whole operand,
// or its last token when options precede it.
std::string texture_operand(TextScan& scan) {
  std::string_view rest = scan.rest();
  if (!rest.empty() && rest.front() == '-') {
    const auto last_blank = rest.find_last_of(" \t");
    if (last_blank != std::string_view::npos) rest.remove_prefix(last_blank + 1);
  }
  return std::string(rest);
}

}  // namespace

bool read_mtl(const std::filesystem::path& mtl_file, std::vector<Material>& materials,
              std::unordered_map<std::string, std::uint32_t>& by_name) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(mtl_file, ec)) return false;
  std::unique_ptr<BufferedInput> opened;
  try {
    opened = std::make_unique<BufferedInput>(mtl_file);
  } catch (const InputError&) {
    return false;
  }
  BufferedInput& in = *opened;
  const auto fail = [&](const std::string& what) {
    throw InputError(in.name(), at_line(in.line_number()), what);
  };

  std::vector<Material> parsed;
  Material* current = nullptr;
  std::string_view line;
  while (in.next_line(line)) {
    TextScan scan(line);
    const std::string_view key = scan.token();
    if (key.empty() || key.front() == '#') continue;
    if (key == "newmtl") {
      parsed.push_back(Material{std::string(scan.rest()), Rgba8{255, 255, 255, 255}, ""});
      current = &parsed.back();
      continue;
    }
    if (!current) continue;  // statements before the first newmtl belong to no material
    if (key == "Kd") {
      scan.skip_blanks();
      if (scan.p < scan.end && (*scan.p == 's' || *scan.p == 'x')) continue;  // "Kd spectral" / "Kd xyz"
      double rgb[3];
      if (!scan.number(rgb[0])) fail("malformed Kd colour");
      rgb[1] = rgb[2] = rgb[0];  // "Kd r" alone means grey
      if (!scan.at_end() && !(scan.number(rgb[1]) && scan.number(rgb[2]))) fail("malformed Kd colour");
      current->color.r = unit_to_byte(rgb[0]);
      current->color.g = unit_to_byte(rgb[1]);
      current->color.b = unit_to_byte(rgb[2]);
    } else if (key == "d" || key == "Tr") {
      scan.skip_blanks();
      if (std::string_view(scan.p, scan.end - scan.p).starts_with("-halo")) scan.token();
      double value;
      if (!scan.number(value)) fail("malformed " + std::string(key) + " value");
      current->color.a = unit_to_byte(key == "d" ? value : 1.0 - value);
    } else if (key == "map_Kd") {
      const std::string texture = texture_operand(scan);
      if (!texture.empty())
        current->texture = locate_referenced_file(mtl_file.parent_path(), texture).string();
    }
  }
  for (Material& material : parsed) {
    by_name[material.name] = static_cast<std::uint32_t>(materials.size());
    materials.push_back(std::move(material));
  }
  return true;
}

}  // namespace cellbake

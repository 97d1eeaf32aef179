#include "pipeline/readers/model_reader.h"

#include <algorithm>
#include <cctype>

#include "pipeline/input_error.h"
#include "pipeline/readers/format_readers.h"
#include "pipeline/readers/isolated_read.h"

namespace cellbake {
namespace {

std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

ModelInfo read_model(const std::filesystem::path& file, const TriangleCallback& emit, const ReadOptions& options) {
  std::string ext = lower_extension(file);
  const bool gzipped = ext == ".gz";
  if (gzipped) ext = lower_extension(file.stem());
  const std::string format = ext.empty() ? std::string() : ext.substr(1);

  if (format == "obj") return read_obj(file, emit, options);
  if (format == "ply") return read_ply(file, emit);
  if (format == "off") return read_off(file, emit);
  if (format == "stl") return read_stl(file, emit);
  if (!format.empty() && assimp_supports(format)) {
    if (!options.import_in_child_process) return read_with_assimp(file, format, gzipped, emit, options);
    return read_in_child_process(
        file, "assimp",
        [&](const TriangleCallback& emit_in_child) {
          return read_with_assimp(file, format, gzipped, emit_in_child, options);
        },
        emit, IsolationLimits{options.import_memory_bytes, options.import_seconds});
  }
  throw InputError(file.string(), "", "unknown model format '" + ext + "'");
}

std::string describe_vertex_colours(const ModelInfo& info) {
  const Rgba8& c = info.uniform_vertex_colour;
  const std::string colour = std::to_string(c.r) + " " + std::to_string(c.g) + " " + std::to_string(c.b) +
                             (c.a == 255 ? "" : " " + std::to_string(c.a));
  switch (info.vertex_colours) {
    case VertexColourUse::none: return "";
    case VertexColourUse::varying:
      return "vertex colours: used (they vary; multiplied into the material colour where a face has one)";
    case VertexColourUse::uniform_ignored:
      return "vertex colours: ignored (all equal: " + colour + "), material colours used";
    case VertexColourUse::uniform_kept:
      return "vertex colours: all equal (" + colour + "), used: no material colour to prefer" +
             (c.r == 0 && c.g == 0 && c.b == 0 ? std::string(" (the model is black)") : std::string());
  }
  return "";
}

}  // namespace cellbake

#include "pipeline/export/glb_builder.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace cellbake {
namespace {

constexpr std::uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

std::uint32_t get_u32(std::span<const std::uint8_t> bytes, std::size_t at) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= std::uint32_t(bytes[at + i]) << (8 * i);
  return v;
}

std::size_t padded(std::size_t n) { return (n + 3) & ~std::size_t{3}; }

}  // namespace

GlbBuilder::GlbBuilder() {
  json_["asset"] = {{"version", "2.0"}, {"generator", "cellbake export"}};
}

void GlbBuilder::align_bin() { bin_.resize(padded(bin_.size()), 0); }

void GlbBuilder::use_extension(const std::string& name, bool required) {
  const auto add = [&name](nlohmann::json& list) {
    if (!list.is_array()) list = nlohmann::json::array();
    if (std::find(list.begin(), list.end(), name) == list.end()) list.push_back(name);
  };
  add(json_["extensionsUsed"]);
  if (required) add(json_["extensionsRequired"]);
}

int GlbBuilder::reserve_buffer_view() {
  nlohmann::json& views = json_["bufferViews"];
  views.push_back(nlohmann::json::object());
  return static_cast<int>(views.size()) - 1;
}

int GlbBuilder::add_buffer_view(std::span<const std::uint8_t> bytes, std::optional<int> byte_stride,
                                std::optional<int> target) {
  const int view = reserve_buffer_view();
  fill_buffer_view(view, bytes, byte_stride, target);
  return view;
}

void GlbBuilder::fill_buffer_view(int index, std::span<const std::uint8_t> bytes, std::optional<int> byte_stride,
                                  std::optional<int> target) {
  align_bin();
  nlohmann::json view{{"buffer", 0}, {"byteOffset", bin_.size()}, {"byteLength", bytes.size()}};
  if (byte_stride) view["byteStride"] = *byte_stride;
  if (target) view["target"] = *target;
  bin_.insert(bin_.end(), bytes.begin(), bytes.end());
  json_["bufferViews"][std::size_t(index)] = std::move(view);
}

int GlbBuilder::add_compressed_buffer_view(std::span<const std::uint8_t> compressed, std::size_t count,
                                           int byte_stride, MeshoptMode mode, std::optional<int> target) {
  const int view = reserve_buffer_view();
  fill_compressed_buffer_view(view, compressed, count, byte_stride, mode, target);
  return view;
}

void GlbBuilder::fill_compressed_buffer_view(int index, std::span<const std::uint8_t> compressed, std::size_t count,
                                             int byte_stride, MeshoptMode mode, std::optional<int> target) {
  use_extension("EXT_meshopt_compression", true);
  align_bin();
  nlohmann::json ext{{"buffer", 0},
                     {"byteOffset", bin_.size()},
                     {"byteLength", compressed.size()},
                     {"byteStride", byte_stride},
                     {"count", count},
                     {"mode", mode == MeshoptMode::attributes ? "ATTRIBUTES" : "TRIANGLES"}};
  bin_.insert(bin_.end(), compressed.begin(), compressed.end());
  const std::size_t length = count * static_cast<std::size_t>(byte_stride);
  fallback_bytes_ = padded(fallback_bytes_);
  nlohmann::json view{{"buffer", 1}, {"byteOffset", fallback_bytes_}, {"byteLength", length}};
  fallback_bytes_ += length;
  if (mode == MeshoptMode::attributes) view["byteStride"] = byte_stride;
  if (target) view["target"] = *target;
  view["extensions"]["EXT_meshopt_compression"] = std::move(ext);
  json_["bufferViews"][std::size_t(index)] = std::move(view);
}

int GlbBuilder::add_accessor(int buffer_view, int component_type, bool normalized, std::size_t count,
                             const std::string& type, const std::vector<double>& min, const std::vector<double>& max,
                             std::size_t byte_offset) {
  nlohmann::json a{{"bufferView", buffer_view}, {"componentType", component_type}, {"count", count}, {"type", type}};
  if (byte_offset > 0) a["byteOffset"] = byte_offset;
  if (normalized) a["normalized"] = true;
  if (!min.empty()) a["min"] = min;
  if (!max.empty()) a["max"] = max;
  nlohmann::json& accessors = json_["accessors"];
  accessors.push_back(std::move(a));
  return static_cast<int>(accessors.size()) - 1;
}

std::vector<std::uint8_t> GlbBuilder::finish() {
  align_bin();
  nlohmann::json doc = json_;
  nlohmann::json buffers = nlohmann::json::array();
  if (!bin_.empty() || fallback_bytes_ > 0) buffers.push_back({{"byteLength", bin_.size()}});
  if (fallback_bytes_ > 0)
    buffers.push_back({{"byteLength", fallback_bytes_}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
  if (!buffers.empty()) doc["buffers"] = std::move(buffers);
  std::string text = doc.dump();
  text.resize(padded(text.size()), ' ');
  const std::size_t total = 12 + 8 + text.size() + (bin_.empty() ? 0 : 8 + bin_.size());
  if (total > std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("glb: the file would be " + std::to_string(total) + " bytes, over the format's 4 GiB");
  std::vector<std::uint8_t> out;
  out.reserve(total);
  put_u32(out, kMagic);
  put_u32(out, 2);
  put_u32(out, static_cast<std::uint32_t>(total));
  put_u32(out, static_cast<std::uint32_t>(text.size()));
  put_u32(out, kChunkJson);
  out.insert(out.end(), text.begin(), text.end());
  if (!bin_.empty()) {
    put_u32(out, static_cast<std::uint32_t>(bin_.size()));
    put_u32(out, kChunkBin);
    out.insert(out.end(), bin_.begin(), bin_.end());
  }
  return out;
}

ParsedGlb parse_glb(std::span<const std::uint8_t> bytes) {
  if (bytes.size() < 20) throw std::runtime_error("glb: " + std::to_string(bytes.size()) + " bytes, too short for a header");
  if (get_u32(bytes, 0) != kMagic) throw std::runtime_error("glb: no 'glTF' magic");
  ParsedGlb glb;
  glb.version = get_u32(bytes, 4);
  if (glb.version != 2) throw std::runtime_error("glb: version " + std::to_string(glb.version) + ", not 2");
  if (get_u32(bytes, 8) != bytes.size())
    throw std::runtime_error("glb: header length " + std::to_string(get_u32(bytes, 8)) + " but the file has " +
                             std::to_string(bytes.size()) + " bytes");
  std::size_t at = 12;
  bool have_json = false;
  while (at < bytes.size()) {
    if (bytes.size() - at < 8) throw std::runtime_error("glb: truncated chunk header at byte " + std::to_string(at));
    const std::uint32_t length = get_u32(bytes, at), type = get_u32(bytes, at + 4);
    if (length % 4 != 0) throw std::runtime_error("glb: chunk at byte " + std::to_string(at) + " is not 4-byte aligned");
    if (length > bytes.size() - at - 8)
      throw std::runtime_error("glb: chunk at byte " + std::to_string(at) + " runs past the end");
    const auto data = bytes.subspan(at + 8, length);
    if (!have_json) {
      if (type != kChunkJson) throw std::runtime_error("glb: the first chunk is not JSON");
      try {
        glb.json = nlohmann::json::parse(data.begin(), data.end());
      } catch (const nlohmann::json::exception& e) {
        throw std::runtime_error(std::string("glb: JSON chunk: ") + e.what());
      }
      have_json = true;
    } else if (type == kChunkBin) {
      if (!glb.bin.empty()) throw std::runtime_error("glb: two BIN chunks");
      glb.bin.assign(data.begin(), data.end());
    }  // other chunk types are skipped, as the specification asks
    at += 8 + length;
  }
  if (!have_json) throw std::runtime_error("glb: no JSON chunk");
  return glb;
}

}  // namespace cellbake

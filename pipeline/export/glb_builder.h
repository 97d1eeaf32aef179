// The glTF 2.0 binary container (Khronos glTF 2.0 specification, section 4.4
// "GLB File Format Specification"): a 12-byte header, a JSON chunk (padded
// with spaces) and a BIN chunk (padded with zeros), every chunk and every
// buffer view 4-byte aligned. GlbBuilder collects the JSON document and the
// binary buffer as a file is assembled; parse_glb reads one back (the tests'
// round trip, and a check on what export writes). Buffer views compressed
// with meshoptimizer (EXT_meshopt_compression) keep their uncompressed size
// in a second, data-less "fallback" buffer, as that extension specifies.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace cellbake {

// glTF accessor component types and buffer view targets.
namespace gltf {
constexpr int kByte = 5120, kUnsignedByte = 5121, kShort = 5122, kUnsignedShort = 5123, kUnsignedInt = 5125,
              kFloat = 5126;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;
}  // namespace gltf

// How a compressed buffer view was coded (EXT_meshopt_compression `mode`).
enum class MeshoptMode { attributes, triangles };

class GlbBuilder {
 public:
  GlbBuilder();

  // The document being built ("asset" is set; buffers, bufferViews and
  // accessors are added by the calls below; the rest is the caller's).
  nlohmann::json& json() { return json_; }

  // Appends `bytes` to the BIN chunk at a 4-byte boundary and returns the new
  // buffer view's index. `byte_stride` (> 0) is written for vertex streams,
  // `target` (gltf::kArrayBuffer ...) when given.
  int add_buffer_view(std::span<const std::uint8_t> bytes, std::optional<int> byte_stride = {},
                      std::optional<int> target = {});
  // A buffer view whose data is stored compressed (EXT_meshopt_compression):
  // `compressed` (meshopt_encodeVertexBuffer / meshopt_encodeIndexBuffer
  // output for `count` elements of `byte_stride` bytes) goes into the BIN
  // chunk; the view itself points into the fallback buffer with the
  // uncompressed length count * byte_stride. Marks the extension used and
  // required. Returns the view's index.
  int add_compressed_buffer_view(std::span<const std::uint8_t> compressed, std::size_t count, int byte_stride,
                                 MeshoptMode mode, std::optional<int> target = {});
  // Reserves the index of a buffer view whose data comes later, so that
  // accessors can name it first; fill_buffer_view / fill_compressed_buffer_view
  // (the add_ calls' arguments) give it its data, before finish().
  int reserve_buffer_view();
  void fill_buffer_view(int view, std::span<const std::uint8_t> bytes, std::optional<int> byte_stride,
                        std::optional<int> target);
  void fill_compressed_buffer_view(int view, std::span<const std::uint8_t> compressed, std::size_t count,
                                   int byte_stride, MeshoptMode mode, std::optional<int> target);
  // Adds an accessor over `buffer_view` from `byte_offset` and returns its index.
  // `min` / `max` are written when non-empty (positions need them).
  int add_accessor(int buffer_view, int component_type, bool normalized, std::size_t count, const std::string& type,
                   const std::vector<double>& min = {}, const std::vector<double>& max = {},
                   std::size_t byte_offset = 0);
  // Adds `name` to extensionsUsed (and extensionsRequired when `required`), once.
  void use_extension(const std::string& name, bool required);

  // The finished file: header, JSON chunk, BIN chunk (omitted when empty).
  // Throws std::length_error when the file would exceed 4 GiB (the format's
  // 32-bit length).
  std::vector<std::uint8_t> finish();

  std::size_t bin_bytes() const { return bin_.size(); }

 private:
  void align_bin();
  nlohmann::json json_;
  std::vector<std::uint8_t> bin_;
  std::size_t fallback_bytes_ = 0;  // the EXT_meshopt_compression fallback buffer's length
};

// A GLB file read back.
struct ParsedGlb {
  std::uint32_t version = 0;
  nlohmann::json json;
  std::vector<std::uint8_t> bin;  // empty when the file has no BIN chunk
};

// Reads a GLB file's bytes: checks the magic "glTF", version 2, the total
// length against the byte count, the chunk lengths and types (JSON first,
// then an optional BIN), 4-byte alignment, and parses the JSON. Throws
// std::runtime_error("glb: ...") naming what is wrong.
ParsedGlb parse_glb(std::span<const std::uint8_t> bytes);

}  // namespace cellbake

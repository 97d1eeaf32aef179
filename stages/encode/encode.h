// Stage `encode`: compact, deterministic byte encodings of a cell's far field —
// each cube face's colour image (JPEG / WebP / PNG through OpenImageIO, in
// memory; AVIF / JPEG XL through libavif / libjxl) and each face's textured depth mesh (quantised positions and
// texture coordinates, meshoptimizer vertex and index codecs; Kapoulkine,
// meshoptimizer, https://github.com/zeux/meshoptimizer). Decoders take
// untrusted bytes: they validate everything and throw std::runtime_error,
// never crash.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "stages/cube_map.h"
#include "stages/geometry.h"

namespace cellbake {

// ------------------------------------------------------------------ images

struct ImageEncodeParams {
  std::string format = "jpeg";  // "jpeg" | "webp" | "png" | "avif" | "jxl"
  int quality = 85;             // 1..100 for the lossy formats; ignored by png (lossless)
};

struct DecodedImage {
  int width = 0, height = 0;
  std::vector<Rgba8> pixels;  // row-major, row 0 at the top, width * height
};

// Encodes a row-major RGBA8 image (row 0 at the top) as format `params.format`.
// JPEG, AVIF and JPEG XL have no alpha here: alpha is dropped (decode gives
// 255). PNG is lossless; WebP at quality 100 is still lossy. Same input and params -> same bytes.
// Throws std::invalid_argument for an empty or mis-sized image, an unknown
// format or a quality outside 1..100, and std::runtime_error("encode_image: ...")
// when OpenImageIO fails.
std::vector<std::uint8_t> encode_image(const std::vector<Rgba8>& pixels, int width, int height,
                                       const ImageEncodeParams& params);

// Decodes bytes from encode_image (format sniffed from the magic bytes: PNG,
// JPEG, WebP, AVIF, JPEG XL), on the calling thread alone. Grey and grey+alpha images are expanded to RGBA; images without
// alpha get 255. Throws std::runtime_error("image blob: ...") on anything it
// cannot decode, including images above 16384 pixels on a side or 2^26 pixels
// in all, and on damaged images a decoder would fill in: a PNG or JPEG cut
// short (no IEND chunk / EOI marker at the end) or one its decoder warns
// about. Never crashes on garbage.
// The format of encoded image bytes, told by their magic bytes as
// decode_image tells it: "jpeg", "webp", "png", "avif", "jxl" (the names
// encode_image takes), or "" when none of them.
std::string encoded_image_format(const std::vector<std::uint8_t>& bytes);

DecodedImage decode_image(const std::uint8_t* data, std::size_t size);
inline DecodedImage decode_image(const std::vector<std::uint8_t>& bytes) {
  return decode_image(bytes.data(), bytes.size());
}

// ------------------------------------------------------------- face meshes

struct MeshEncodeParams {
  // Grid coding (blob version 2, stages/encode/encode_grid_mesh.h): when `face` is a
  // cube face (0..5) and `face_size` > 0, a mesh whose vertices all lie on the
  // eye rays through pixel corners of that face (as depth meshes do) is coded
  // as pixel corners + log-quantised depth, relative depth error at most
  // `depth_error_relative`. Other meshes, or face = -1, use version 1.
  int face = -1;
  int face_size = 0;
  double depth_error_relative = 0.001;
  // zstd level of the grid coding's streams (1..22; the decoder accepts any).
  // 15 is the knee of size against time on real faces: level 19 makes them
  // 0.9 % smaller in three times the time (docs/benchmark-history.md, issue #12).
  int zstd_level = 15;
  // Version 1: bits per position axis (1..16), quantised over the mesh's own
  // bounds; see face_mesh_position_error_bound for the resulting error.
  int position_bits = 16;
  // Reorder triangles for the vertex cache and vertices for fetch before
  // encoding (meshoptimizer), which shrinks the index stream ~2x. The decoded
  // mesh then has the same triangles (same winding, corners possibly rotated)
  // in a different order. When false, the order of triangles is kept.
  bool optimize_order = true;
};

// Encodes a face mesh. Version 2 (grid coding, see MeshEncodeParams): a
// 48-byte header (magic "CBFM", version, face, face size, counts, depth step)
// and a zstd frame of the index stream and the predicted pixel-corner and
// depth residuals; pixel corners are exact, depths within
// depth_error_relative, always in vertex-cache order. Version 1: a 64-byte
// little-endian header (magic "CBFM", version, bits, counts, position and uv
// bounds, stream sizes), then the meshoptimizer-encoded vertex stream
// (quantised x, y, z at position_bits and u, v at 16 bits, as uint16) and
// index stream. Same input and params -> same bytes. Throws
// std::invalid_argument("encode_face_mesh: ...") for a non-finite position or
// uv, an index out of range, an index count not a multiple of 3, uvs not
// matching positions, or bits outside 1..16.
std::vector<std::uint8_t> encode_face_mesh(const FaceMesh& mesh, const MeshEncodeParams& params);

// Decodes bytes from encode_face_mesh, either version (databases baked before
// the grid coding still open). Validates every length, count, bound,
// quantised value and index; throws std::runtime_error("face mesh blob: ...")
// on anything wrong. Memory use is bounded by a small multiple of `size`.
FaceMesh decode_face_mesh(const std::uint8_t* data, std::size_t size);
inline FaceMesh decode_face_mesh(const std::vector<std::uint8_t>& bytes) {
  return decode_face_mesh(bytes.data(), bytes.size());
}

// Largest per-axis position error (same units as the positions) that encoding
// `mesh` at `position_bits` can introduce: half a quantisation step of the
// widest axis, (max - min) / (2^bits - 1) / 2, plus float32 rounding of the
// decoded value. Texture coordinates: (max - min) / 65535 / 2 plus rounding.
double face_mesh_position_error_bound(const FaceMesh& mesh, int position_bits);
double face_mesh_uv_error_bound(const FaceMesh& mesh);

}  // namespace cellbake

// libFuzzer target: decode_chunk_blob (storage/chunk_codec.h) on arbitrary
// bytes; a blob that decodes must hold consistent arrays and re-encode.
#include <exception>

#include "storage/chunk_codec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cellbake::Chunk chunk;
  try {
    cellbake::decode_chunk_blob(data, size, chunk);
  } catch (const std::exception&) {
    return 0;
  }
  const std::size_t n = chunk.positions.size();
  if (chunk.colors.size() != n || (!chunk.uvs.empty() && chunk.uvs.size() != n) ||
      (!chunk.normals.empty() && chunk.normals.size() != n) || chunk.indices.size() % 3 != 0 ||
      (!chunk.materials.empty() && chunk.materials.size() != chunk.triangle_count()))
    __builtin_trap();
  for (std::uint32_t i : chunk.indices)
    if (i >= n) __builtin_trap();
  try {
    cellbake::encode_chunk_blob(chunk);
  } catch (const std::exception&) {
  }
  return 0;
}

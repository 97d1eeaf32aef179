// libFuzzer target: decode_face_mesh (stages/encode/encode.h, blob versions 1 and 2)
// on arbitrary bytes; a mesh that decodes must have its indices in range.
#include <exception>

#include "stages/encode/encode.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  cellbake::FaceMesh mesh;
  try {
    mesh = cellbake::decode_face_mesh(data, size);
  } catch (const std::exception&) {
    return 0;
  }
  if (mesh.indices.size() % 3 != 0 || (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size()))
    __builtin_trap();
  for (std::uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) __builtin_trap();
  return 0;
}

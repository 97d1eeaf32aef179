#include "storage/cell_content_hash.h"

#include "stages/hashing.h"

namespace cellbake {

std::string cell_content_hash(const CellRow& row) {
  Hasher h;
  h.u64(row.id).f64(row.cull_half_size).u64(row.near_triangles);
  for (const auto& n : row.near_chunks) h.u64(std::uint64_t(n.chunk_id)).u64(n.triangles).u64(n.whole);
  for (const auto& s : row.samples) {
    h.u64(s.index).f64(s.eye.x).f64(s.eye.y).f64(s.eye.z).u64(std::uint64_t(std::int64_t(s.parent)));
    h.f64(s.void_after).u64(s.covered_pixels).u64(s.removed_pixels);
    for (const auto& f : s.faces) {
      h.u64(f.face).text(f.image_format).bytes(f.image.data(), f.image.size()).u64(f.image.size());
      h.bytes(f.mesh.data(), f.mesh.size()).u64(f.mesh.size());
    }
  }
  return h.hex();
}

}  // namespace cellbake

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
  // Exact far geometry (issue #13); cells without any hash as before it existed.
  if (!row.far_geometry.empty() || !row.far_choice.empty()) {
    h.text("far").u64(row.far_geometry_triangles);
    for (const auto& g : row.far_geometry) {
      h.u64(std::uint64_t(g.chunk_id)).u64(g.triangles).u64(g.whole).f64(g.origin.x).f64(g.origin.y).f64(g.origin.z);
      h.f64(g.bounds.lo.x).f64(g.bounds.lo.y).f64(g.bounds.lo.z).f64(g.bounds.hi.x).f64(g.bounds.hi.y).f64(g.bounds.hi.z);
      h.bytes(g.geometry.data(), g.geometry.size()).u64(g.geometry.size());
      // A simplified level (issue #35); level 0 rows hash as before it existed.
      if (g.level != 0) h.text("level").u64(std::uint64_t(std::int64_t(g.level)));
    }
    for (const auto& f : row.far_choice)
      h.u64(std::uint64_t(f.face)).u64(f.geometry_tiles).u64(f.tdm_triangles).u64(f.replaced_triangles).u64(f.geometry_triangles);
  }
  return h.hex();
}

}  // namespace cellbake

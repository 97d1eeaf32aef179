#include "viewer/decoded_cell.h"

#include <stdexcept>
#include <string>

namespace cellbake {

std::size_t DecodedCell::bytes() const {
  std::size_t b = near_ids.size() * sizeof(std::int64_t);
  for (const DecodedFace& f : faces)
    b += f.mesh.positions.size() * sizeof(Vec3f) + f.mesh.uvs.size() * sizeof(Uv) +
         f.mesh.indices.size() * sizeof(std::uint32_t) + f.image.pixels.size() * sizeof(Rgba8);
  return b;
}

DecodedCell decode_cell(const CellRow& row) {
  const std::string where = "cell " + std::to_string(row.id);
  if (row.status != "done") throw std::runtime_error(where + " is not baked (status " + row.status + ")");
  DecodedCell cell;
  cell.id = row.id;
  cell.bounds = row.bounds;
  cell.cull_box = Box3d::cube(row.bounds.center(), row.cull_half_size);
  cell.near_triangles = row.near_triangles;
  for (const NearChunkRow& n : row.near_chunks) cell.near_ids.push_back(n.chunk_id);
  for (const SampleRow& s : row.samples) {
    SampleNode node;
    node.index = s.index;
    node.eye = s.eye;
    node.parent = s.parent;
    for (const FaceRow& f : s.faces) {
      const std::string face = where + " sample " + std::to_string(s.index) + " face " + std::to_string(f.face);
      if (f.face < 0 || f.face >= kCubeFaces) throw std::runtime_error(face + ": face index out of range");
      DecodedFace d;
      d.sample = s.index;
      d.face = f.face;
      d.eye = s.eye;
      try {
        d.mesh = decode_face_mesh(f.mesh);
        d.image = decode_image(f.image);
      } catch (const std::exception& e) {
        throw std::runtime_error(face + ": " + e.what());
      }
      for (const Uv& uv : d.mesh.uvs)
        if (!(uv.u >= 0 && uv.u <= 1 && uv.v >= 0 && uv.v <= 1))
          throw std::runtime_error(face + ": texture coordinate outside [0, 1]");
      for (const Vec3f& p : d.mesh.positions) d.bounds.expand(s.eye + Vec3d{p.x, p.y, p.z});
      cell.far_triangles += d.mesh.triangle_count();
      node.triangles += d.mesh.triangle_count();
      cell.faces.push_back(std::move(d));
    }
    cell.samples.push_back(node);
  }
  return cell;
}

}  // namespace cellbake

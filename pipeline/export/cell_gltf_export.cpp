#include "pipeline/export/cell_gltf_export.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include "pipeline/export/affine_face_mesh.h"
#include "pipeline/export/glb_builder.h"
#include "pipeline/export/gltf_image.h"
#include "pipeline/export/gltf_vertex_streams.h"
#include "stages/chunk_lod.h"
#include "stages/encode/encode.h"
#include "storage/chunk_codec.h"

namespace cellbake {
namespace {

using nlohmann::json;

json vec(const Vec3d& v) { return json::array({v.x, v.y, v.z}); }
json box(const Box3d& b) { return {{"min", vec(b.lo)}, {"max", vec(b.hi)}}; }

// glTF sampler values.
constexpr int kLinear = 9729, kLinearMipmapLinear = 9987;
constexpr int kRepeat = 10497, kClampToEdge = 33071, kMirroredRepeat = 33648;

int gl_wrap(TextureWrap w) {
  return w == TextureWrap::clamp ? kClampToEdge : (w == TextureWrap::mirror ? kMirroredRepeat : kRepeat);
}

// A mesh and the node transform that dequantises its positions.
struct PlacedMesh {
  int mesh = -1;  // -1: nothing to draw
  PositionQuantization q;
};

class SceneWriter {
 public:
  SceneWriter(const ChunkSource& store, const GltfSceneContext& context, const GltfExportOptions& options,
              const Vec3d& origin, std::vector<Box3d> cell_boxes)
      : store_(store),
        context_(context),
        options_(options),
        origin_(origin),
        cell_boxes_(std::move(cell_boxes)),
        materials_(store.materials()) {}

  GlbBuilder& glb() { return glb_; }
  // The file, its pooled streams written.
  std::vector<std::uint8_t> finish() {
    streams_.flush();
    return glb_.finish();
  }
  GltfExportStats& stats() { return stats_; }

  int add_node(json node) {
    json& nodes = glb_.json()["nodes"];
    nodes.push_back(std::move(node));
    return static_cast<int>(nodes.size()) - 1;
  }
  void add_child(int parent, int child) { glb_.json()["nodes"][parent]["children"].push_back(child); }

  // A node drawing `placed` (nothing when it draws nothing); returns its index or -1.
  int mesh_node(const std::string& name, const PlacedMesh& placed) {
    if (placed.mesh < 0) return -1;
    const double s = placed.q.scale;
    return add_node({{"name", name}, {"mesh", placed.mesh}, {"translation", vec(placed.q.translation)},
                     {"scale", {s, s, s}}});
  }

  // A store chunk's mesh, made once (near fields and whole far chunks share it).
  PlacedMesh store_chunk(std::int64_t id, bool near) {
    if (auto it = chunk_meshes_.find(id); it != chunk_meshes_.end()) return it->second;
    const std::shared_ptr<const Chunk> chunk = store_.load(id);
    if (!chunk) throw std::runtime_error("chunk " + std::to_string(id) + ": the store returned no geometry");
    (near ? stats_.near_triangles : stats_.far_geometry_triangles) += chunk->triangle_count();
    count_stored(id, 0, *chunk);
    return chunk_meshes_[id] = chunk_mesh(*chunk, "chunk " + std::to_string(id), chunk_tolerance(chunk->bounds));
  }

  // A far piece's mesh: levels are shared by cache id, cut pieces are the cell's own.
  PlacedMesh far_piece(const DecodedFarPiece& piece) {
    const bool shared = piece.level != 0;
    if (shared)
      if (auto it = level_meshes_.find(piece.cache_id); it != level_meshes_.end()) return it->second;
    const std::shared_ptr<const Chunk> chunk = far_piece_chunk(piece, store_);
    stats_.far_geometry_triangles += chunk->triangle_count();
    const std::string name = "chunk " + std::to_string(piece.chunk_id) +
                             (shared ? " level " + std::to_string(piece.level) : " (part)");
    if (shared)
      count_stored(piece.chunk_id, piece.level, *chunk);
    else if (!stored_blobs_.contains({piece.chunk_id, 0}))
      count_stored(piece.chunk_id, 0, *store_.load(piece.chunk_id));  // a part is cut out of the whole
    const PlacedMesh placed = chunk_mesh(*chunk, name, chunk_tolerance(piece.bounds));
    if (shared) level_meshes_[piece.cache_id] = placed;
    return placed;
  }

  // One face of a sample: its refined depth mesh textured with its image.
  PlacedMesh face_mesh(const DecodedFace& face, const FaceRow* stored, const std::string& name) {
    FaceMesh mesh = face.mesh;
    snap_to_sample_rays(mesh, face.face);
    const AffineRefinement refined =
        refine_for_affine_uvs(mesh, face.face, face.image.width, face.image.height, options_.uv_tolerance_px);
    stats_.depth_mesh_triangles += mesh.triangle_count();
    stats_.depth_mesh_triangles_out += refined.mesh.triangle_count();
    if (refined.mesh.indices.empty()) return {};
    ExportMesh e;
    const Vec3d offset = face.eye - origin_;
    e.positions.reserve(refined.mesh.positions.size());
    for (const Vec3f& p : refined.mesh.positions) e.positions.push_back(offset + Vec3d{p.x, p.y, p.z});
    e.uvs = refined.mesh.uvs;  // u right, v down: glTF's convention already
    e.indices = refined.mesh.indices;
    const int subpixels = options_.uv_subpixels;
    if (subpixels > 0 && std::int64_t(face.image.width) * subpixels <= 65535 &&
        std::int64_t(face.image.height) * subpixels <= 65535) {
      e.uv_grid_width = face.image.width * subpixels;
      e.uv_grid_height = face.image.height * subpixels;
    }
    // The mesh's positions within a fraction of its nearest vertex's distance from the sample eye.
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vec3f& p : refined.mesh.positions) nearest = std::min(nearest, length(Vec3d{p.x, p.y, p.z}));
    std::vector<ExportMesh> primitives(1, std::move(e));
    const int material = face_material(face, stored, name, primitives[0].uv_grid_width, primitives[0].uv_grid_height);
    return add_mesh(name, primitives, {material}, options_.depth_mesh_tolerance * nearest);
  }

 private:
  // Position tolerance of chunk geometry within `bounds`: the fixed one, or
  // the distance fraction of its distance from the nearest exported cell.
  double chunk_tolerance(const Box3d& bounds) const {
    double distance = std::numeric_limits<double>::infinity();
    for (const Box3d& cell : cell_boxes_) distance = std::min(distance, box_distance(cell, bounds));
    if (!std::isfinite(distance)) distance = 0;
    return std::max(options_.position_tolerance, options_.position_tolerance_per_distance * distance);
  }

  // Counts the stored blob of chunk `id` at `level` (0: the chunk) once.
  void count_stored(std::int64_t id, int level, const Chunk& chunk) {
    if (!stored_blobs_.insert({id, level}).second) return;
    ++stats_.store_chunks;
    stats_.store_chunk_bytes += encode_chunk_blob(chunk).size();
  }

  // The chunk's triangles lit with the bake's light model, one primitive per material.
  PlacedMesh chunk_mesh(const Chunk& c, const std::string& name, double tolerance) {
    std::map<int, ExportMesh> by_material;  // key: glTF material
    const Vec3d offset = c.origin - origin_;
    const std::size_t triangles = c.triangle_count();
    for (std::size_t t = 0; t < triangles; ++t) {
      const std::uint32_t material = c.materials.empty() ? 0 : c.materials[t];
      const bool textured = !c.uvs.empty() && material < materials_.size() && materials_[material].texture_id > 0;
      ExportMesh& e = by_material[geometry_material(textured ? int(material) : -1)];
      std::array<Vec3d, 3> p;
      for (int k = 0; k < 3; ++k) p[k] = offset + to_double(c.positions[c.indices[3 * t + k]]);
      Vec3d face_normal = cross(p[1] - p[0], p[2] - p[0]);
      const double face_length = length(face_normal);
      face_normal = face_length > 0 && std::isfinite(face_length) ? face_normal * (1.0 / face_length) : Vec3d{};
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = c.indices[3 * t + k];
        Vec3d n = face_normal;
        if (!c.normals.empty()) {
          const Vec3d vn = to_double(c.normals[v]);
          if (dot(vn, vn) > 1e-6) n = vn * (1.0 / length(vn));
        }
        // The shader keeps the base colour where it finds no normal.
        const double factor = dot(n, n) > 0 ? lighting_factor(context_.lights, n) : 1.0;
        Rgba8 colour = apply_lighting(c.colors.empty() ? Rgba8{} : c.colors[v], factor);
        colour.a = 255;
        e.indices.push_back(static_cast<std::uint32_t>(e.positions.size()));
        e.positions.push_back(p[k]);
        if (options_.normals) e.normals.push_back({static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)});
        e.colors.push_back(colour);
        if (textured) {
          e.uvs.push_back({c.uvs[v].u, 1.0f - c.uvs[v].v});  // the store's origin is bottom-left, glTF's top-left
        }
      }
    }
    std::vector<ExportMesh> primitives;
    std::vector<int> material_of;
    for (auto& [material, e] : by_material) {
      // A material group mixing textured and untextured corners cannot occur: the key says which.
      primitives.push_back(std::move(e));
      material_of.push_back(material);
    }
    return add_mesh(name, primitives, material_of, tolerance);
  }

  static Vec3d to_double(const Vec3f& p) { return {p.x, p.y, p.z}; }

  // The primitives as one mesh, positions quantised to the fewest bits that keep them within `tolerance`.
  PlacedMesh add_mesh(const std::string& name, std::vector<ExportMesh>& primitives, const std::vector<int>& materials,
                      double tolerance) {
    Box3d bounds;
    for (ExportMesh& e : primitives) {
      weld_vertices(e);
      optimize_mesh_order(e);
      for (const Vec3d& p : e.positions) bounds.expand(p);
    }
    if (bounds.empty()) return {};
    PlacedMesh placed;
    placed.q = position_quantization(bounds, position_bits_within(bounds, tolerance));
    json list = json::array();
    for (std::size_t k = 0; k < primitives.size(); ++k) {
      if (primitives[k].indices.empty()) continue;
      json primitive = add_primitive_streams(streams_, primitives[k], placed.q, options_.color_bits);
      primitive["material"] = materials[k];
      list.push_back(std::move(primitive));
    }
    if (list.empty()) return {};
    json& meshes = glb_.json()["meshes"];
    meshes.push_back({{"name", name}, {"primitives", std::move(list)}});
    ++stats_.meshes;
    placed.mesh = static_cast<int>(meshes.size()) - 1;
    return placed;
  }

  int add_material(json material) {
    glb_.use_extension("KHR_materials_unlit", false);
    material["doubleSided"] = true;
    material["extensions"]["KHR_materials_unlit"] = json::object();
    json& list = glb_.json()["materials"];
    list.push_back(std::move(material));
    return static_cast<int>(list.size()) - 1;
  }

  // -1: every untextured triangle (colours are per vertex); else the store's material.
  int geometry_material(int store_material) {
    if (auto it = geometry_materials_.find(store_material); it != geometry_materials_.end()) return it->second;
    json pbr{{"baseColorFactor", {1, 1, 1, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 1}};
    json material{{"name", "geometry"}};
    if (store_material >= 0) {
      const Material& m = materials_[std::size_t(store_material)];
      material["name"] = m.name.empty() ? "material " + std::to_string(store_material) : m.name;
      pbr["baseColorTexture"] = {{"index", store_texture(m.texture_id)}};
      if (m.alpha_test) {
        material["alphaMode"] = "MASK";
        material["alphaCutoff"] = 0.5;
      }
    }
    material["pbrMetallicRoughness"] = std::move(pbr);
    return geometry_materials_[store_material] = add_material(std::move(material));
  }

  int add_sampler(int mag, int min, int wrap_s, int wrap_t) {
    const std::array<int, 4> key{mag, min, wrap_s, wrap_t};
    if (auto it = samplers_.find(key); it != samplers_.end()) return it->second;
    json& list = glb_.json()["samplers"];
    list.push_back({{"magFilter", mag}, {"minFilter", min}, {"wrapS", wrap_s}, {"wrapT", wrap_t}});
    return samplers_[key] = static_cast<int>(list.size()) - 1;
  }

  int add_image(std::span<const std::uint8_t> bytes, const std::string& mime) {
    const int view = glb_.add_buffer_view(bytes);
    json& list = glb_.json()["images"];
    list.push_back({{"bufferView", view}, {"mimeType", mime}});
    ++stats_.images;
    stats_.image_bytes += bytes.size();
    return static_cast<int>(list.size()) - 1;
  }

  // A texture of `image`; `extension` (EXT_texture_avif / EXT_texture_webp) names it instead of `source`.
  int add_texture(int image, int sampler, const std::string& extension = "") {
    json texture{{"sampler", sampler}};
    if (extension.empty()) {
      texture["source"] = image;
    } else {
      glb_.use_extension(extension, true);
      texture["extensions"][extension] = {{"source", image}};
    }
    json& list = glb_.json()["textures"];
    list.push_back(std::move(texture));
    return static_cast<int>(list.size()) - 1;
  }

  // A material texture of the store, re-encoded (PNG with alpha, else JPEG), once.
  int store_texture(std::int64_t id) {
    if (auto it = store_textures_.find(id); it != store_textures_.end()) return it->second;
    const std::shared_ptr<const TextureImage> t = store_.load_texture(id);
    if (!t || t->width < 1 || t->height < 1)
      throw std::runtime_error("texture " + std::to_string(id) + ": the store returned no image");
    std::vector<Rgba8> rows(t->texels.size());  // top row first, as image files hold them
    for (int y = 0; y < t->height; ++y)
      std::copy_n(t->texels.begin() + std::ptrdiff_t(y) * t->width, t->width,
                  rows.begin() + std::ptrdiff_t(t->height - 1 - y) * t->width);
    const GltfImage encoded = encode_gltf_image(rows, t->width, t->height, t->has_alpha, options_.jpeg_quality);
    ++stats_.images_reencoded;
    const int image = add_image(encoded.bytes, encoded.mime_type);
    const int sampler = add_sampler(kLinear, kLinearMipmapLinear, gl_wrap(t->wrap_u), gl_wrap(t->wrap_v));
    return store_textures_[id] = add_texture(image, sampler);
  }

  // The face's image as stored when glTF (or, compressed, an extension) can
  // hold it, else re-encoded as JPEG; an unlit, clamped, linearly filtered material.
  // With a uv grid (ExportMesh::uv_grid_width), KHR_texture_transform scales the grid's integers back.
  int face_material(const DecodedFace& face, const FaceRow* stored, const std::string& name, int uv_grid_width,
                    int uv_grid_height) {
    const int sampler = add_sampler(kLinear, kLinear, kClampToEdge, kClampToEdge);
    const std::string format = stored ? stored->image_format : "";
    int texture;
    if (format == "png" || format == "jpeg") {
      texture = add_texture(add_image(stored->image, "image/" + format), sampler);
    } else if (options_.compress && (format == "avif" || format == "webp")) {
      texture = add_texture(add_image(stored->image, "image/" + format), sampler, "EXT_texture_" + format);
    } else {
      const DecodedImage& im = face.image;
      GltfImage encoded;
      try {
        encoded = encode_gltf_image(im.pixels, im.width, im.height, false, options_.jpeg_quality);
      } catch (const std::exception& e) {
        throw std::runtime_error(name + ": " + e.what());
      }
      ++stats_.images_reencoded;
      texture = add_texture(add_image(encoded.bytes, encoded.mime_type), sampler);
    }
    json pbr{{"baseColorFactor", {1, 1, 1, 1}},
             {"metallicFactor", 0},
             {"roughnessFactor", 1},
             {"baseColorTexture", {{"index", texture}}}};
    if (uv_grid_width > 0) {
      glb_.use_extension("KHR_texture_transform", true);
      pbr["baseColorTexture"]["extensions"]["KHR_texture_transform"] = {
          {"scale", {1.0 / uv_grid_width, 1.0 / uv_grid_height}}};
    }
    return add_material({{"name", name}, {"pbrMetallicRoughness", std::move(pbr)}});
  }

  const ChunkSource& store_;
  GltfSceneContext context_;
  GltfExportOptions options_;
  Vec3d origin_;
  std::vector<Box3d> cell_boxes_;  // the exported cells' bounds: where the eye may be
  std::vector<Material> materials_;
  GlbBuilder glb_;
  StreamPool streams_{glb_, options_.compress};
  GltfExportStats stats_;
  std::map<std::int64_t, PlacedMesh> chunk_meshes_, level_meshes_;
  std::set<std::pair<std::int64_t, int>> stored_blobs_;  // (chunk, level) counted in stats_.store_chunk_bytes
  std::map<int, int> geometry_materials_;
  std::map<std::int64_t, int> store_textures_;
  std::map<std::array<int, 4>, int> samplers_;
};

const FaceRow* stored_face(const CellRow& row, int sample, int face) {
  for (const SampleRow& s : row.samples)
    if (s.index == sample)
      for (const FaceRow& f : s.faces)
        if (f.face == face) return &f;
  return nullptr;
}

json cell_extras(const CellRow& row, const DecodedCell& cell) {
  json samples = json::array();
  for (const SampleNode& s : cell.samples) samples.push_back({{"index", s.index}, {"eye", vec(s.eye)}, {"parent", s.parent}});
  return {{"cell_id", cell.id},
          {"grid", {row.gx, row.gy, row.gz}},
          {"bounds", box(cell.bounds)},
          {"centre", vec(cell.bounds.center())},
          {"cull_box", box(cell.cull_box)},
          {"samples", std::move(samples)},
          {"near_chunks", cell.near_ids},
          {"near_triangles", cell.near_triangles},
          {"far_triangles", cell.far_triangles},
          {"far_geometry_triangles", cell.far_geometry_triangles}};
}

}  // namespace

std::vector<std::uint8_t> export_cells_glb(const std::vector<CellToExport>& cells, const ChunkSource& store,
                                           const GltfSceneContext& context, const GltfExportOptions& options,
                                           GltfExportStats* stats_out) {
  if (cells.empty()) throw std::invalid_argument("glTF export: no cells to export");
  const bool z_up = context.up == Vec3d{0, 0, 1};
  if (!z_up && context.up != Vec3d{0, 1, 0}) throw std::invalid_argument("glTF export: up must be +z or +y");
  for (const CellToExport& c : cells)
    if (!c.row || !c.cell) throw std::invalid_argument("glTF export: a cell without its row or decoded cell");
  const Vec3d origin = cells.front().cell->bounds.center();
  std::vector<Box3d> cell_boxes;
  for (const CellToExport& c : cells) cell_boxes.push_back(c.cell->bounds);
  SceneWriter w(store, context, options, origin, std::move(cell_boxes));

  json root{{"name", "cellbake " + context.database_name}};
  // The model's up axis onto glTF's +Y: z-up turns -90 degrees about x, (x, y, z) -> (x, z, -y).
  if (z_up) root["rotation"] = {-std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};
  json ids = json::array();
  for (const CellToExport& c : cells) ids.push_back(c.cell->id);
  root["extras"]["cellbake"] = {{"database", context.database_name},
                                {"origin", vec(origin)},
                                {"up", z_up ? "z" : "y"},
                                {"cells", ids},
                                {"lighting", "baked into COLOR_0 and the face images (KHR_materials_unlit)"},
                                {"note", "positions are relative to origin (world coordinates, model units); "
                                         "bounds, eyes and boxes in extras are world coordinates"}};
  const int root_node = w.add_node(std::move(root));

  for (const CellToExport& c : cells) {
    const DecodedCell& cell = *c.cell;
    const std::string where = "cell " + std::to_string(cell.id);
    const int cell_node = w.add_node({{"name", where}, {"extras", {{"cellbake", cell_extras(*c.row, cell)}}}});
    w.add_child(root_node, cell_node);
    // A group node over `children` under `parent`, only when it has any (glTF: children, if present, is non-empty).
    const auto group = [&](int parent, const std::string& name, const std::vector<int>& children) {
      if (children.empty()) return;
      const int node = w.add_node({{"name", name}});
      for (int child : children) w.add_child(node, child);
      w.add_child(parent, node);
    };
    const auto keep = [](std::vector<int>& list, int node) {
      if (node >= 0) list.push_back(node);
    };
    try {
      std::vector<int> near, far;
      for (std::int64_t id : cell.near_ids) keep(near, w.mesh_node("chunk " + std::to_string(id), w.store_chunk(id, true)));
      group(cell_node, "near field", near);
      for (const DecodedFarPiece& p : cell.far_pieces)
        keep(far, w.mesh_node("chunk " + std::to_string(p.chunk_id), w.far_piece(p)));
      for (std::int64_t id : cell.far_whole_ids)
        keep(far, w.mesh_node("chunk " + std::to_string(id), w.store_chunk(id, false)));
      group(cell_node, "far geometry", far);
      std::map<int, std::vector<int>> faces_of_sample;
      for (const DecodedFace& f : cell.faces) {
        const std::string name = where + " sample " + std::to_string(f.sample) + " face " + std::to_string(f.face);
        keep(faces_of_sample[f.sample],
             w.mesh_node("face " + std::to_string(f.face), w.face_mesh(f, stored_face(*c.row, f.sample, f.face), name)));
      }
      std::vector<int> samples;
      for (const auto& [sample, faces] : faces_of_sample) {
        if (faces.empty()) continue;
        const int node = w.add_node({{"name", "sample " + std::to_string(sample)}});
        for (int face : faces) w.add_child(node, face);
        samples.push_back(node);
      }
      group(cell_node, "far field", samples);
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      if (what.rfind(where, 0) == 0) throw;
      throw std::runtime_error(where + ": " + what);
    }
    ++w.stats().cells;
  }
  w.glb().json()["scenes"] = json::array({{{"name", "cellbake"}, {"nodes", {root_node}}}});
  w.glb().json()["scene"] = 0;
  std::vector<std::uint8_t> bytes = w.finish();
  w.stats().bytes = bytes.size();
  if (stats_out) *stats_out = w.stats();
  return bytes;
}

}  // namespace cellbake

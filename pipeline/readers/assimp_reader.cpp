// Every format without a streaming reader of our own goes through the Open
// Asset Import Library (assimp), which loads the whole scene: polygons are
// triangulated, points and lines are dropped, and each mesh is emitted once
// per node that places it, under the node's world transform composed in
// double (assimp's own aiProcess_PreTransformVertices works in float, which
// loses centimetres 1e6 m from the origin, and crashes on some files: an
// assertion on OpenGEX scenes, a segfault on RAW ones); meshes no node places
// are not part of the scene and are skipped with a warning. Material i of the scene becomes
// material i + 1 of ours (0 stays the default grey). Vertex colours (set 0)
// multiply material colours only when they vary across the scene; all equal,
// the material colour wins (model_reader.h). Normals are the file's when it
// has them (none are generated: faces without stay flat). A material's base
// colour (glTF) or else diffuse texture is returned as a TextureInput: the
// embedded image's bytes or texels, or the external file resolved against the
// model's folder, with the material's wrap modes; a glTF material whose alpha
// mode is OPAQUE never alpha-tests. Every file assimp opens itself (glTF
// buffers, ...) goes through ContainedIOSystem, which refuses those outside
// the model's folder (contained_paths.h) unless ReadOptions allow them.
// Assimp's own warnings and errors during the import (faces it dropped,
// materials it could not find) become the model's warnings (assimp_messages.h).
#include <assimp/DefaultIOSystem.h>
#include <assimp/config.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/assimp_messages.h"
#include "pipeline/readers/buffered_input.h"
#include "pipeline/readers/collada_node_graph.h"
#include "pipeline/readers/colour_math.h"
#include "pipeline/readers/contained_paths.h"
#include "pipeline/readers/format_readers.h"
#include "pipeline/readers/gltf_node_graph.h"
#include "pipeline/readers/directx_nesting.h"
#include "pipeline/readers/markup_nesting.h"

namespace cellbake {
namespace {

constexpr unsigned kImportFlags = aiProcess_Triangulate | aiProcess_SortByPType;

// Deeper node hierarchies are refused as malformed.
constexpr int kMaxNodeDepth = 1024;

// A ".gz" model is decompressed into memory for assimp: at most this much.
constexpr std::uint64_t kMaxDecompressedBytes = std::uint64_t{4} << 30;

std::uint32_t u32_le(const unsigned char* p) {
  return p[0] | p[1] << 8 | p[2] << 16 | std::uint32_t(p[3]) << 24;
}

// Throws InputError unless the GLB's header length and every chunk length fit
// in the `size` bytes it has; `read(offset, n, dst)` reads bytes of the file.
// Run before assimp, which allocates what a chunk header declares.
template <class Read>
void check_glb_lengths(const std::string& name, std::uint64_t size, Read&& read) {
  unsigned char head[12];
  if (size < 12 || !read(0, 12, head) || std::memcmp(head, "glTF", 4) != 0) return;  // assimp reports it
  const std::uint64_t declared = u32_le(head + 8);
  if (declared > size)
    throw InputError(name, at_byte(8),
                     "GLB header declares " + std::to_string(declared) + " bytes but the file has " +
                         std::to_string(size));
  for (std::uint64_t at = 12; at + 8 <= declared;) {
    unsigned char chunk[8];
    if (!read(at, 8, chunk)) break;
    const std::uint64_t length = u32_le(chunk);
    if (at + 8 + length > declared)
      throw InputError(name, at_byte(at),
                       "GLB chunk declares " + std::to_string(length) + " bytes but only " +
                           std::to_string(declared - at - 8) + " follow in the file");
    at += 8 + length;
  }
}

// The decompressed size a gzip file's trailer states (ISIZE: the size modulo
// 2^32, exact for the single-member files gzip writes under 4 GiB); 0 when
// unreadable. Only a hint for reserving memory.
std::uint64_t gzip_size_hint(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  unsigned char trailer[4];
  if (!in.seekg(-4, std::ios::end) || !in.read(reinterpret_cast<char*>(trailer), 4)) return 0;
  return u32_le(trailer);
}

// Formats assimp reads as XML, whose importers recurse per element level.
bool xml_format(const std::string& extension) {
  for (const char* xml : {"dae", "x3d", "xml", "irr", "irrmesh", "amf", "xgl"})
    if (extension == xml) return true;
  return false;
}

// The checks before import over the whole file's bytes `data` (a decompressed
// ".gz", or a glTF read whole): JSON, XML or DirectX text nesting
// (markup_nesting.h, directx_nesting.h) and a
// glTF or COLLADA node graph (gltf_node_graph.h, collada_node_graph.h). Throws InputError naming `name`.
void check_before_import(const std::string& name, const std::string& extension, const char* data,
                         std::size_t size) {
  if (extension == "gltf") {
    check_markup_nesting(name, data, size);
    check_gltf_node_graph(name, data, size);
  } else if (extension == "glb") {
    const auto [at, length] = glb_json_chunk(reinterpret_cast<const unsigned char*>(data), size);
    check_markup_nesting(name, data + at, length);
    check_gltf_node_graph(name, data + at, length);
  } else if (xml_format(extension)) {
    check_markup_nesting(name, data, size);
    if (extension == "dae") check_collada_node_graph(name, data, size);
  } else if (extension == "x") {
    check_directx_nesting(name, data, size);
  }
}

// check_before_import for a plain file: XML is scanned as it is read; glTF
// JSON (a .gltf file, a GLB's JSON chunk) is read whole for its node graph.
void check_file_before_import(const std::string& name, const std::string& extension,
                              const std::filesystem::path& file) {
  if (xml_format(extension)) {
    check_markup_nesting_of_file(name, file);
    if (extension == "dae") check_collada_node_graph_of_file(name, file);
    return;
  }
  if (extension == "x") {
    check_directx_nesting_of_file(name, file);
    return;
  }
  if (extension != "gltf" && extension != "glb") return;
  std::ifstream in(file, std::ios::binary);
  std::vector<char> bytes;
  if (extension == "gltf") {
    bytes.resize(std::filesystem::file_size(file));
  } else {  // the 20-byte header and the JSON chunk (check_glb_lengths has checked the lengths)
    unsigned char head[20];
    if (!in.read(reinterpret_cast<char*>(head), 20)) return;
    bytes.assign(head, head + 20);
    const std::size_t length = glb_json_chunk(head, 20 + std::size_t(u32_le(head + 12))).second;
    if (length == 0) return;
    bytes.resize(20 + length);
  }
  in.read(bytes.data() + (extension == "glb" ? 20 : 0),
          std::streamsize(bytes.size() - (extension == "glb" ? 20 : 0)));
  if (!in) return;  // assimp reports what it cannot read
  check_before_import(name, extension, bytes.data(), bytes.size());
}

// The files assimp opens, checked against the model's folder. Relative names
// are resolved against `base` (assimp joins references to the folder of the
// path it was given, so `base` is empty; a model read from memory gets bare
// references, resolved against its folder). Refused names are kept for the
// warnings and errors; writes are always refused.
class ContainedIOSystem : public Assimp::DefaultIOSystem {
 public:
  ContainedIOSystem(std::filesystem::path folder, std::filesystem::path base, bool allow_outside)
      : folder_(std::move(folder)), base_(std::move(base)), allow_outside_(allow_outside) {}

  bool Exists(const char* file) const override {
    const std::string path = resolve(file);
    return allowed(file, path) && DefaultIOSystem::Exists(path.c_str());
  }

  Assimp::IOStream* Open(const char* file, const char* mode = "rb") override {
    const std::string path = resolve(file);
    if (!mode || mode[0] != 'r' || !allowed(file, path)) return nullptr;
    return DefaultIOSystem::Open(path.c_str(), mode);
  }

  const std::vector<std::string>& refused() const { return refused_; }

 private:
  std::string resolve(const char* file) const {
    const std::filesystem::path p(file ? file : "");
    return (p.is_absolute() || base_.empty() ? p : base_ / p).string();
  }

  bool allowed(const char* name, const std::string& path) const {
    if (allow_outside_ || path_inside_folder(folder_, path)) return true;
    if (std::find(refused_.begin(), refused_.end(), name) == refused_.end()) refused_.emplace_back(name);
    return false;
  }

  std::filesystem::path folder_, base_;
  bool allow_outside_;
  mutable std::vector<std::string> refused_;  // Exists() is const
};

TextureWrap wrap_of(int mode) {
  switch (mode) {
    case aiTextureMapMode_Clamp:
    case aiTextureMapMode_Decal:
      return TextureWrap::clamp;
    case aiTextureMapMode_Mirror:
      return TextureWrap::mirror;
    default:
      return TextureWrap::repeat;
  }
}

// The texture `reference` of a material of `scene` read from `file`.
TextureInput texture_input(const aiScene& scene, const aiMaterial& material, aiTextureType type,
                           const std::string& reference, const std::filesystem::path& file) {
  TextureInput input;
  int mode = aiTextureMapMode_Wrap;
  if (material.Get(AI_MATKEY_MAPPINGMODE_U(type, 0), mode) == AI_SUCCESS) input.wrap_u = wrap_of(mode);
  if (material.Get(AI_MATKEY_MAPPINGMODE_V(type, 0), mode) == AI_SUCCESS) input.wrap_v = wrap_of(mode);
  aiString alpha_mode;
  if (material.Get("$mat.gltf.alphaMode", 0, 0, alpha_mode) == AI_SUCCESS)
    input.alpha_allowed = std::string(alpha_mode.C_Str()) != "OPAQUE";
  if (const aiTexture* embedded = scene.GetEmbeddedTexture(reference.c_str())) {
    if (embedded->mHeight == 0) {  // compressed: mWidth is the byte count
      const auto* bytes = reinterpret_cast<const std::uint8_t*>(embedded->pcData);
      input.encoded.assign(bytes, bytes + embedded->mWidth);
      input.format_hint = embedded->achFormatHint;
    } else {
      input.width = static_cast<int>(embedded->mWidth);
      input.height = static_cast<int>(embedded->mHeight);
      input.texels.reserve(std::size_t(embedded->mWidth) * embedded->mHeight);
      for (unsigned i = 0; i < embedded->mWidth * embedded->mHeight; ++i) {
        const aiTexel& t = embedded->pcData[i];
        input.texels.push_back({t.r, t.g, t.b, t.a});
      }
    }
    return input;
  }
  input.file = locate_referenced_file(file.parent_path(), reference);
  return input;
}

Material convert_material(const aiMaterial& source) {
  Material material;
  aiString name;
  if (source.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) material.name = name.C_Str();
  aiColor4D colour(1, 1, 1, 1);
  if (source.Get(AI_MATKEY_BASE_COLOR, colour) != AI_SUCCESS) source.Get(AI_MATKEY_COLOR_DIFFUSE, colour);
  float opacity = 1;
  if (source.Get(AI_MATKEY_OPACITY, opacity) == AI_SUCCESS) colour.a *= opacity;
  material.color = {unit_to_byte(colour.r), unit_to_byte(colour.g), unit_to_byte(colour.b),
                    unit_to_byte(colour.a)};
  aiString texture;
  if (source.GetTexture(aiTextureType_BASE_COLOR, 0, &texture) == AI_SUCCESS ||
      source.GetTexture(aiTextureType_DIFFUSE, 0, &texture) == AI_SUCCESS)
    material.texture = texture.C_Str();
  return material;
}

Rgba8 vertex_colour_of(const aiColor4D& c) {
  return {unit_to_byte(c.r), unit_to_byte(c.g), unit_to_byte(c.b), unit_to_byte(c.a)};
}

// Every vertex colour of the scene (set 0 of each mesh), for the "do they vary" rule.
ColourVariation scene_colour_variation(const aiScene& scene) {
  ColourVariation variation;
  for (unsigned m = 0; m < scene.mNumMeshes && !variation.varies; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    if (!mesh.mColors[0]) continue;
    for (unsigned v = 0; v < mesh.mNumVertices && !variation.varies; ++v)
      variation.add(vertex_colour_of(mesh.mColors[0][v]));
  }
  return variation;
}

// A node's affine transform in double, row-major 3x4 (assimp's matrices are
// row-major too, translation in the fourth column).
struct Affine {
  double m[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
  Vec3d point(double x, double y, double z) const {
    return {m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3],
            m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3],
            m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3]};
  }
};

Affine affine_of(const aiMatrix4x4& a) {
  const float* rows[3] = {&a.a1, &a.b1, &a.c1};
  Affine t;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) t.m[r][c] = rows[r][c];
  return t;
}

// parent * child.
Affine compose(const Affine& parent, const Affine& child) {
  Affine t;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) {
      double sum = c == 3 ? parent.m[r][3] : 0;
      for (int k = 0; k < 3; ++k) sum += parent.m[r][k] * child.m[k][c];
      t.m[r][c] = sum;
    }
  return t;
}

// The transpose of the inverse of the linear part (adjugate over determinant,
// whose sign alone matters once normals are renormalised): maps normals.
std::array<std::array<double, 3>, 3> normal_matrix(const Affine& t) {
  const auto& m = t.m;
  std::array<std::array<double, 3>, 3> n{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
      n[r][c] = m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1];  // cofactor (r, c)
    }
  const double det = m[0][0] * n[0][0] + m[0][1] * n[0][1] + m[0][2] * n[0][2];
  if (det < 0)
    for (auto& row : n)
      for (double& v : row) v = -v;
  return n;
}

struct MeshInstance {
  unsigned mesh = 0;
  Affine world;
};

// Every (mesh, world transform) the node tree places, depth first in child
// order; without a root node every mesh once, untransformed. Throws
// InputError for a mesh index out of range, a non-finite transform or a tree
// deeper than kMaxNodeDepth.
std::vector<MeshInstance> placed_meshes(const aiScene& scene, const std::string& file) {
  std::vector<MeshInstance> placed;
  if (!scene.mRootNode) {
    for (unsigned m = 0; m < scene.mNumMeshes; ++m) placed.push_back({m, Affine{}});
    return placed;
  }
  struct Pending {
    const aiNode* node;
    Affine parent;
    int depth;
  };
  std::vector<Pending> stack{{scene.mRootNode, Affine{}, 0}};
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    if (p.depth > kMaxNodeDepth)
      throw InputError(file, "", "node hierarchy deeper than " + std::to_string(kMaxNodeDepth) + " levels");
    const Affine world = compose(p.parent, affine_of(p.node->mTransformation));
    for (const auto& row : world.m)
      for (double v : row)
        if (!std::isfinite(v))
          throw InputError(file, std::string("node '") + p.node->mName.C_Str() + "'", "non-finite transform");
    for (unsigned i = 0; i < p.node->mNumMeshes; ++i) {
      const unsigned m = p.node->mMeshes[i];
      if (m >= scene.mNumMeshes)
        throw InputError(file, std::string("node '") + p.node->mName.C_Str() + "'",
                         "mesh index " + std::to_string(m) + " out of range");
      placed.push_back({m, world});
    }
    for (unsigned c = p.node->mNumChildren; c-- > 0;)  // reversed: popped in child order
      if (p.node->mChildren[c]) stack.push_back({p.node->mChildren[c], world, p.depth + 1});
  }
  return placed;
}

// Emits the mesh's triangles under `world`; `colours_vary` is the scene-wide
// rule's verdict. Returns true when some corner's uniform vertex colour gave
// way to its material's.
bool emit_mesh(const std::string& file, unsigned mesh_index, const aiMesh& mesh, const Affine& world,
               bool colours_vary, ModelInfo& info, const TriangleCallback& emit) {
  const std::uint32_t material_index = mesh.mMaterialIndex + 1;
  const Rgba8 material_colour =
      material_index < info.materials.size() ? info.materials[material_index].color : info.materials[0].color;
  const aiColor4D* colours = mesh.mColors[0];
  const aiVector3D* texcoords = mesh.mTextureCoords[0];
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    const aiVector3D& p = mesh.mVertices[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InputError(file, "mesh " + std::to_string(mesh_index) + " vertex " + std::to_string(v),
                       "non-finite coordinate");
  }
  bool ignored = false;
  const auto normals = normal_matrix(world);
  Triangle t;
  t.material = material_index < info.materials.size() ? material_index : 0;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;  // points and lines carry no surface
    for (int i = 0; i < 3; ++i) {
      const unsigned v = face.mIndices[i];
      if (v >= mesh.mNumVertices)
        throw InputError(file, "mesh " + std::to_string(mesh_index) + " face " + std::to_string(f),
                         "vertex index " + std::to_string(v) + " out of range");
      t.p[i] = world.point(mesh.mVertices[v].x, mesh.mVertices[v].y, mesh.mVertices[v].z);
      Rgba8 vertex_colour;
      if (colours) vertex_colour = vertex_colour_of(colours[v]);
      t.color[i] =
          corner_colour(material_colour, t.material, colours ? &vertex_colour : nullptr, colours_vary);
      ignored |= colours && t.material != 0 && !colours_vary;
      if (texcoords) t.uv[i] = {texcoords[v].x, texcoords[v].y};
      if (mesh.mNormals) {
        const aiVector3D& a = mesh.mNormals[v];
        double n[3];
        for (int r = 0; r < 3; ++r) n[r] = normals[r][0] * a.x + normals[r][1] * a.y + normals[r][2] * a.z;
        const double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const double scale = length > 0 ? 1 / length : 0;  // a zero normal stays zero (ingest checks normals)
        t.normal[i] = {float(n[0] * scale), float(n[1] * scale), float(n[2] * scale)};
      }
    }
    t.has_normals = mesh.mNormals != nullptr;
    emit(t);
    ++info.triangles_emitted;
  }
  return ignored;
}

// The up axis of what assimp hands over (the root node's transform applied):
// glTF is Y-up by specification; assimp rotates IFC (Z-up) and COLLADA files
// to Y-up; other importers (FBX, ...) may record the file's axis in the scene
// metadata "UpAxis" (0 = x, 1 = y, 2 = z) with "UpAxisSign" without rotating.
void detect_up_axis(const aiScene& scene, const std::string& extension, ModelInfo& info) {
  if (extension == "gltf" || extension == "glb") {
    info.up = "y", info.up_source = "glTF is Y-up by specification";
  } else if (extension == "ifc" || extension == "ifczip") {
    info.up = "y", info.up_source = "assimp turns IFC's Z-up into Y-up";
  } else if (extension == "dae" || extension == "zae") {  // .zae: zipped COLLADA
    info.up = "y", info.up_source = "assimp turns COLLADA files into Y-up";
  } else if (scene.mMetaData) {
    std::int32_t axis = -1, sign = 1;
    if (!scene.mMetaData->Get("UpAxis", axis)) return;
    scene.mMetaData->Get("UpAxisSign", sign);
    if (sign < 0 || (axis != 1 && axis != 2)) return;  // x or downward axes: not one we bake
    info.up = axis == 1 ? "y" : "z";
    info.up_source = "the file's UpAxis metadata";
  }
}

}  // namespace

bool assimp_supports(const std::string& extension) {
  const AssimpMessages serialised;  // every use of assimp holds its process-wide logger (assimp_messages.h)
  Assimp::Importer importer;
  return importer.IsExtensionSupported("." + extension);
}

ModelInfo read_with_assimp(const std::filesystem::path& file, const std::string& extension, bool gzipped,
                           const TriangleCallback& emit, const ReadOptions& options) {
  const std::string name = file.string();
  const AssimpMessages messages;  // what assimp says while reading (outlives the importer, which logs too)
  Assimp::Importer importer;
  // The importer owns and deletes the IOSystem.
  auto* io = new ContainedIOSystem(file.parent_path(), gzipped ? file.parent_path() : std::filesystem::path(),
                                   options.allow_outside_paths);
  importer.SetIOHandler(io);
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = nullptr;
  if (gzipped) {
    std::vector<char> bytes;
    BufferedInput in(file);  // refuses decompression bombs (kMaxGzipRatio)
    const std::uint64_t allowed = std::max(kGzipFloorBytes, std::filesystem::file_size(file) * kMaxGzipRatio);
    bytes.reserve(std::min({gzip_size_hint(file), kMaxDecompressedBytes, allowed}));  // no regrowth copies
    while (const char* p = in.fetch(1)) {
      const std::size_t n = in.buffered();
      if (bytes.size() + n > kMaxDecompressedBytes)
        throw InputError(name, "",
                         "decompresses to more than " + std::to_string(kMaxDecompressedBytes >> 30) +
                             " GiB, the cap for compressed models read whole");
      bytes.insert(bytes.end(), p, p + n);
      in.consume(n);
    }
    if (extension == "glb")
      check_glb_lengths(name, bytes.size(), [&](std::uint64_t at, std::size_t n, unsigned char* dst) {
        if (at + n > bytes.size()) return false;
        std::memcpy(dst, bytes.data() + at, n);
        return true;
      });
    check_before_import(name, extension, bytes.data(), bytes.size());
    scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), kImportFlags, extension.c_str());
  } else {
    require_regular_file(file);
    if (extension == "glb") {
      std::ifstream in(file, std::ios::binary);
      check_glb_lengths(name, std::filesystem::file_size(file),
                        [&](std::uint64_t at, std::size_t n, unsigned char* dst) {
                          in.seekg(std::streamoff(at));
                          return bool(in.read(reinterpret_cast<char*>(dst), std::streamsize(n)));
                        });
    }
    check_file_before_import(name, extension, file);
    scene = importer.ReadFile(name, kImportFlags);
  }
  if (!scene && !io->refused().empty())
    throw InputError(name, "",
                     "needs '" + io->refused().front() + "', " + kOutsideFolder +
                         " (assimp: " + importer.GetErrorString() + ")");
  if (!scene) throw InputError(name, "", std::string("assimp: ") + importer.GetErrorString());

  ModelInfo info;
  for (const std::string& refused : io->refused())
    info.warnings.push_back(" reference '" + refused + "': " + kOutsideFolder);
  for (std::string& said : messages.warnings()) info.warnings.push_back(std::move(said));
  info.format = "assimp:" + extension;
  detect_up_axis(*scene, extension, info);
  info.materials.push_back(default_material());
  for (unsigned m = 0; m < scene->mNumMaterials; ++m) {
    const aiMaterial& material = *scene->mMaterials[m];
    info.materials.push_back(convert_material(material));
    for (aiTextureType type : {aiTextureType_BASE_COLOR, aiTextureType_DIFFUSE}) {
      aiString reference;
      if (material.GetTexture(type, 0, &reference) != AI_SUCCESS) continue;
      info.textures[m + 1] = texture_input(*scene, material, type, reference.C_Str(), file);
      break;
    }
  }
  // The scene-wide rule: do the vertex colours vary anywhere?
  const ColourVariation variation = scene_colour_variation(*scene);
  bool ignored = false;
  const std::vector<MeshInstance> placed = placed_meshes(*scene, name);
  std::vector<bool> used(scene->mNumMeshes, false);
  for (const MeshInstance& instance : placed) {
    used[instance.mesh] = true;
    ignored |= emit_mesh(name, instance.mesh, *scene->mMeshes[instance.mesh], instance.world,
                         variation.varies, info, emit);
  }
  if (const auto unplaced = std::count(used.begin(), used.end(), false); unplaced > 0)
    info.warnings.push_back(" " + std::to_string(unplaced) + " of " + std::to_string(scene->mNumMeshes) +
                            " meshes are placed by no node of the scene and were skipped");
  record_vertex_colour_use(info, variation, ignored);
  return info;
}

}  // namespace cellbake

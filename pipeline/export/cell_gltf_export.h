// View cells as one glTF 2.0 binary file (.glb), drawn as cellbake's viewer
// draws them (viewer/scene_drawer.h): the near field's chunks whole, the exact
// far geometry (pieces cut out of store chunks, simplified levels, whole
// chunks), and every sample's textured depth meshes with their face images.
// Chunks are lit as the bake lit them (stages/shading.h: the light
// model is view-independent) and the lit colours are stored per vertex under
// KHR_materials_unlit, so a viewer shows what `cellbake render` shows; the
// face images already hold lit colours. Positions are quantised
// (KHR_mesh_quantization, pipeline/export/gltf_vertex_streams.h); depth meshes
// are refined so plain texture coordinates stay within a tolerance of the
// projective texturing (pipeline/export/affine_face_mesh.h).
//
// Layout: the scene's root node turns the model's up axis onto glTF's +Y and
// holds the origin (the first cell's centre) in its extras; positions are
// relative to that origin. Under it one node per cell ("cell ID": extras with
// its bounds, cull box and samples, world coordinates), with children "near
// field" (a node per chunk), "far geometry" and "far field" (a node per
// sample, a child per face). Meshes of store chunks are shared by every cell
// that draws them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/shading.h"
#include "storage/cell_db.h"
#include "viewer/decoded_cell.h"

namespace cellbake {

struct GltfExportOptions {
  // meshoptimizer's vertex and index codecs on every stream
  // (EXT_meshopt_compression, required), and face images kept as stored when
  // AVIF or WebP (EXT_texture_avif / EXT_texture_webp, required). Web viewers
  // (three.js, Babylon.js) read it; Blender does not.
  bool compress = false;
  // Largest texture error of a depth-mesh edge drawn with plain texture
  // coordinates, face pixels (affine_face_mesh.h).
  double uv_tolerance_px = 0.5;
  // Bits of the linear vertex colours: 8 (0.1 dB below 16 against `cellbake
  // render` on the demo, 10 % smaller compressed) or 16 (no banding in the
  // darks). Whether chunks carry normals: the unlit materials do not use
  // them (and they split vertices), a user relighting the model elsewhere does.
  int color_bits = 8;
  bool normals = false;
  // Largest position error of chunk geometry (near field, exact far
  // geometry), model units: each mesh's positions take the fewest bits
  // (8..16) that keep within it (1 mm: a third of a pixel at 1 m in a
  // 512 x 384 view of 60 degrees; the demo's chunks take 11 to 16 bits).
  double position_tolerance = 0.001;
  // ... or, where larger, this fraction of the chunk's distance from the
  // nearest exported cell (any eye in a cell is at least that far): a tenth
  // of a pixel at every distance in the view above, a quarter in 1920 x 1080
  // at 60 degrees; 0: the fixed tolerance everywhere. The demo's depth-mesh
  // cell: 1.29x -> 1.17x its stored bytes, 34.1 -> 33.0 dB against `cellbake
  // render` (the dense pipe wall's aliasing moves with sub-pixel shifts).
  double position_tolerance_per_distance = 0.0003;
  // The same for a depth mesh, as a fraction of its nearest vertex's distance
  // from the sample eye (the depth error the bake's grid coding allows,
  // encode.mesh_depth_error, is 0.001 by default).
  double depth_mesh_tolerance = 0.001;
  // Depth-mesh texture coordinates on a grid of this many steps per face
  // pixel, as integers that the material's KHR_texture_transform (required)
  // scales back (rounding: at most 1 / (2 subpixels) face pixels); 0:
  // uint16 normalised. Grid steps are small integers between neighbouring
  // vertices, which the codec codes in fewer bits (the demo's tdm cell: 21 % smaller uvs at 4).
  int uv_subpixels = 4;
  // JPEG quality of face images and material textures that are re-encoded
  // (stored as AVIF, WebP or JPEG XL; textures without alpha).
  int jpeg_quality = 90;
};

// What the file draws and what it holds.
struct GltfExportStats {
  std::size_t cells = 0, meshes = 0, images = 0;
  std::uint64_t near_triangles = 0;           // triangles of the near fields' chunks (whole), each shared chunk once
  std::uint64_t far_geometry_triangles = 0;   // exact far geometry, each shared chunk once
  std::uint64_t depth_mesh_triangles = 0;     // textured depth meshes as stored
  std::uint64_t depth_mesh_triangles_out = 0; // after refine_for_affine_uvs
  std::uint64_t image_bytes = 0;              // embedded images
  std::uint64_t images_reencoded = 0;
  std::uint64_t bytes = 0;                    // the whole file
  std::uint64_t store_chunks = 0;             // distinct store chunks the meshes come from
  std::uint64_t store_chunk_bytes = 0;        // their stored (encoded) geometry
};

// The scene-wide facts of the cell database the cells come from.
struct GltfSceneContext {
  Vec3d up{0, 0, 1};           // the model's up axis: (0, 0, 1) or (0, 1, 0)
  ShadingLights lights;        // the bake's light model (shading_lights of its config)
  std::string database_name;   // written into the root's extras
};

// A cell to export: its row with blobs (the stored face images are embedded
// as they are when PNG or JPEG) and the same row decoded with the store
// (decode_cell(row, &store): far pieces cut out or loaded).
struct CellToExport {
  const CellRow* row = nullptr;
  const DecodedCell* cell = nullptr;
};

// The GLB file of `cells` (at least one) over geometry store `store`. Throws
// std::invalid_argument for no cells or an up axis other than +z / +y, and
// std::runtime_error naming the cell (and chunk, sample, face) when the store
// lacks a chunk or texture, a face image cannot be re-encoded, or the file
// would exceed the format's 4 GiB.
std::vector<std::uint8_t> export_cells_glb(const std::vector<CellToExport>& cells, const ChunkSource& store,
                                           const GltfSceneContext& context, const GltfExportOptions& options,
                                           GltfExportStats* stats = nullptr);

}  // namespace cellbake

// The node graph of a glTF 2.0 file, checked before assimp imports it. glTF
// nodes name their children by index, so a few KB can describe a chain
// 100,000 deep (assimp's importer recurses once per level and overflows the
// stack) or a DAG in which every node lists the same child twice (2^30
// instance paths after 30 levels: assimp copies the subtree per reference and
// we would place every copy). The graph is measured without walking the
// paths: per node, in post order, its depth, its node copies and its placed
// triangles, all counted with multiplicity and saturating.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace cellbake {

// Limits on a glTF scene, refused before import (docs/reliability.md).
inline constexpr int kMaxGltfNodeDepth = 1024;  // the node walk's own limit
inline constexpr std::uint64_t kMaxGltfNodeInstances =
    1'000'000;  // node copies assimp would make (~1 KB each)
inline constexpr std::uint64_t kMaxGltfPlacedTriangles = 4'294'967'295;  // the store's limit

// What the node graph implies, counted with multiplicity (saturating at UINT64_MAX).
struct GltfNodeGraph {
  int depth = 0;                       // longest root-to-leaf chain, in nodes
  std::uint64_t node_instances = 0;    // node copies the scenes place
  std::uint64_t placed_triangles = 0;  // triangles of the meshes those copies place
};

// Measures the node graph of the glTF JSON `json` (a .gltf file or a GLB's
// JSON chunk). Roots are every scene's nodes, or with no scenes every node no
// other node lists as a child. Child and mesh indices out of range are left
// to the importer (counted as nothing). Throws InputError naming `name` when
// the JSON does not parse (bytes >= 0x80 are accepted anywhere, as assimp's
// parser does) or a node is its own ancestor (a cycle).
GltfNodeGraph measure_gltf_node_graph(const std::string& name, const char* json, std::size_t size);

// measure_gltf_node_graph, then throws InputError naming `name` and the figure
// when the depth, node copies or placed triangles exceed the limits above.
void check_gltf_node_graph(const std::string& name, const char* json, std::size_t size);

// The JSON chunk of a GLB file's bytes: {offset, size}, or {0, 0} when the
// bytes are not a GLB with a JSON chunk that fits.
std::pair<std::size_t, std::size_t> glb_json_chunk(const unsigned char* bytes, std::size_t size);

}  // namespace cellbake

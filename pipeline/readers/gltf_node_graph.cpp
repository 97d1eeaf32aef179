#include "pipeline/readers/gltf_node_graph.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "pipeline/input_error.h"

namespace cellbake {
namespace {

using json = nlohmann::json;

std::uint64_t saturating_add(std::uint64_t a, std::uint64_t b) {
  return a > std::numeric_limits<std::uint64_t>::max() - b ? std::numeric_limits<std::uint64_t>::max()
                                                           : a + b;
}

// A non-negative integer of `value` (key `key`), or -1.
std::int64_t index_of(const json& value, const char* key) {
  const auto it = value.find(key);
  if (it == value.end() || !it->is_number_integer()) return -1;
  const std::int64_t i = it->get<std::int64_t>();
  return i < 0 ? -1 : i;
}

// Elements of the array `key` of `value`, or an empty array.
const json& array_of(const json& value, const char* key) {
  static const json empty = json::array();
  if (!value.is_object()) return empty;
  const auto it = value.find(key);
  return it != value.end() && it->is_array() ? *it : empty;
}

// Triangles each mesh draws: per primitive its index (or else POSITION)
// accessor's count, by the primitive's mode (4 triangles, 5 strip, 6 fan).
std::vector<std::uint64_t> mesh_triangles(const json& doc) {
  const json& accessors = array_of(doc, "accessors");
  std::vector<std::uint64_t> triangles;
  for (const json& mesh : array_of(doc, "meshes")) {
    std::uint64_t sum = 0;
    for (const json& primitive : array_of(mesh, "primitives")) {
      if (!primitive.is_object()) continue;
      std::int64_t accessor = index_of(primitive, "indices");
      if (accessor < 0 && primitive.contains("attributes") && primitive["attributes"].is_object())
        accessor = index_of(primitive["attributes"], "POSITION");
      if (accessor < 0 || std::size_t(accessor) >= accessors.size() || !accessors[accessor].is_object())
        continue;
      const std::int64_t count = index_of(accessors[accessor], "count");
      const std::int64_t mode = primitive.contains("mode") ? index_of(primitive, "mode") : 4;
      if (count < 3) continue;
      if (mode == 4)
        sum = saturating_add(sum, std::uint64_t(count) / 3);
      else if (mode == 5 || mode == 6)
        sum = saturating_add(sum, std::uint64_t(count) - 2);
    }
    triangles.push_back(sum);
  }
  return triangles;
}

}  // namespace

std::pair<std::size_t, std::size_t> glb_json_chunk(const unsigned char* bytes, std::size_t size) {
  if (size < 20 || std::memcmp(bytes, "glTF", 4) != 0) return {0, 0};
  const auto u32 = [&](std::size_t at) {
    return std::uint32_t(bytes[at]) | std::uint32_t(bytes[at + 1]) << 8 | std::uint32_t(bytes[at + 2]) << 16 |
           std::uint32_t(bytes[at + 3]) << 24;
  };
  const std::size_t length = u32(12);
  if (u32(16) != 0x4E4F534Au || length > size - 20) return {0, 0};  // "JSON"
  return {20, length};
}

GltfNodeGraph measure_gltf_node_graph(const std::string& name, const char* text, std::size_t size) {
  // nlohmann's parser is strict about UTF-8, rapidjson (assimp's) is not: a
  // copy with every byte >= 0x80 (valid only inside strings) made ASCII has
  // the same structure and parses wherever assimp's does. JSON that does not
  // parse even so is refused, so no graph reaches assimp unmeasured.
  // (The parser is iterative; the nesting was checked before, so destroying
  // the document recurses at most kMaxMarkupNesting levels.)
  std::string ascii(text, size);
  for (char& c : ascii)
    if (static_cast<unsigned char>(c) >= 0x80) c = '?';
  json doc;
  try {
    doc = json::parse(ascii);
  } catch (const json::parse_error& e) {
    throw InputError(name, at_byte(e.byte), std::string("not valid glTF JSON: ") + e.what());
  }
  GltfNodeGraph graph;
  if (!doc.is_object()) return graph;
  const json& nodes = array_of(doc, "nodes");
  const std::size_t n = nodes.size();
  const std::vector<std::uint64_t> triangles = mesh_triangles(doc);

  std::vector<std::vector<std::size_t>> children(n);
  std::vector<std::uint64_t> own_triangles(n, 0);
  std::vector<bool> is_child(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    for (const json& c : array_of(nodes[i], "children"))
      if (c.is_number_integer() && c.get<std::int64_t>() >= 0 && std::uint64_t(c.get<std::int64_t>()) < n) {
        children[i].push_back(std::size_t(c.get<std::int64_t>()));
        is_child[children[i].back()] = true;
      }
    if (!nodes[i].is_object()) continue;
    const std::int64_t mesh = index_of(nodes[i], "mesh");
    if (mesh >= 0 && std::size_t(mesh) < triangles.size()) own_triangles[i] = triangles[mesh];
  }
  std::vector<std::size_t> roots;
  const json& scenes = array_of(doc, "scenes");
  for (const json& scene : scenes)
    for (const json& r : array_of(scene, "nodes"))
      if (r.is_number_integer() && r.get<std::int64_t>() >= 0 && std::uint64_t(r.get<std::int64_t>()) < n)
        roots.push_back(std::size_t(r.get<std::int64_t>()));
  if (scenes.empty())
    for (std::size_t i = 0; i < n; ++i)
      if (!is_child[i]) roots.push_back(i);

  // Post-order over the DAG (iterative: the chain may be long), each node once.
  enum : char { unseen, open, done };
  std::vector<char> state(n, unseen);
  std::vector<int> depth(n, 0);
  std::vector<std::uint64_t> copies(n, 0), placed(n, 0);
  std::vector<std::pair<std::size_t, std::size_t>> stack;  // node, next child
  for (const std::size_t root : roots) {
    if (state[root] == done) continue;
    stack.push_back({root, 0});
    state[root] = open;
    while (!stack.empty()) {
      auto& [node, next] = stack.back();
      if (next < children[node].size()) {
        const std::size_t child = children[node][next++];
        if (state[child] == open)
          throw InputError(name, "node " + std::to_string(child),
                           "is its own ancestor (a cycle in the node graph)");
        if (state[child] == unseen) {
          state[child] = open;
          stack.push_back({child, 0});
        }
        continue;
      }
      int d = 0;
      std::uint64_t c = 1, t = own_triangles[node];
      for (const std::size_t child : children[node]) {
        d = std::max(d, depth[child]);
        c = saturating_add(c, copies[child]);
        t = saturating_add(t, placed[child]);
      }
      depth[node] = d == std::numeric_limits<int>::max() ? d : d + 1;
      copies[node] = c;
      placed[node] = t;
      state[node] = done;
      stack.pop_back();
    }
  }
  for (const std::size_t root : roots) {
    graph.depth = std::max(graph.depth, depth[root]);
    graph.node_instances = saturating_add(graph.node_instances, copies[root]);
    graph.placed_triangles = saturating_add(graph.placed_triangles, placed[root]);
  }
  return graph;
}

void check_gltf_node_graph(const std::string& name, const char* json_text, std::size_t size) {
  const GltfNodeGraph graph = measure_gltf_node_graph(name, json_text, size);
  const auto shown = [](std::uint64_t v) {
    return v == std::numeric_limits<std::uint64_t>::max() ? std::string("more than 2^64") : std::to_string(v);
  };
  if (graph.depth > kMaxGltfNodeDepth)
    throw InputError(name, "",
                     "node hierarchy " + std::to_string(graph.depth) + " levels deep, more than " +
                         std::to_string(kMaxGltfNodeDepth));
  if (graph.node_instances > kMaxGltfNodeInstances)
    throw InputError(name, "",
                     "node graph places " + shown(graph.node_instances) +
                         " node instances (nodes shared by several parents are copied per path), more than " +
                         std::to_string(kMaxGltfNodeInstances));
  if (graph.placed_triangles > kMaxGltfPlacedTriangles)
    throw InputError(name, "",
                     "node graph places " + shown(graph.placed_triangles) + " triangles, more than " +
                         std::to_string(kMaxGltfPlacedTriangles));
}

}  // namespace cellbake

// The node graph of a COLLADA file, checked before assimp imports it (issue
// #37). Besides nesting <node> elements (bounded by markup_nesting.h), a node
// may place another node by reference (<instance_node url="#id"/>), which
// assimp resolves by copying the referenced subtree, recursively: a chain of
// references 100,000 long is a hierarchy 100,000 deep (the import recurses
// per level), a node that instances itself never ends, and nodes that each
// instance the next twice make 2^30 copies after 30 levels. As for glTF
// (gltf_node_graph.h) the graph is measured without walking its paths: per
// node, in post order, its depth and its node copies with multiplicity
// (saturating), from one streaming pass over the bytes that records only the
// nodes, their ids and names, and their references. The same pass checks the
// index lists and counts assimp trusts (check_lists).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

namespace cellbake {

// Limits on a COLLADA scene, refused before import (docs/reliability.md).
inline constexpr int kMaxColladaNodeDepth = 1024;                     // the node walk's own limit
inline constexpr std::uint64_t kMaxColladaNodeInstances = 1'000'000;  // node copies assimp would make

struct ColladaNodeGraph {
  int depth = 0;                     // longest chain of nodes from a visual scene (counted), in nodes
  std::uint64_t node_instances = 0;  // node copies the visual scenes place (saturating at UINT64_MAX)
};

// Records <node> elements and their <instance_node> references from bytes fed
// in order, in pieces of any size (tags, comments, CDATA, processing
// instructions and declarations may span pieces; quoted attribute values may
// hold '>'). Only the first 4 KiB of a start tag are looked at.
class ColladaNodeScan {
 public:
  ColladaNodeScan();
  ~ColladaNodeScan();
  void feed(const char* data, std::size_t size);
  // The graph of what was fed. Roots are the <visual_scene>s (a node of
  // their own, as in assimp's scene). A reference resolves as assimp looks it
  // up: among the nodes directly inside <library_nodes> by id, else among the
  // visual scenes and their nodes by id or name; it counts every node it
  // could resolve to (an empty one matches nodes without that attribute);
  // unresolved ones count nothing. Throws InputError naming `name` when a
  // node is its own ancestor.
  ColladaNodeGraph measure(const std::string& name) const;
  // Throws InputError naming `name` (and the byte) for what would make
  // assimp's COLLADA reader loop or allocate without bound: a byte other than
  // digits, signs and blanks in an index list (<p>, <vcount>, <v>, <h>: its
  // number loop never advances past it), a `count` attribute of an array,
  // accessor or primitive larger than the bytes fed (it reserves that many
  // values), a <vcount> whose numbers sum to more than the bytes fed, an
  // <accessor> of a float_array in this document that reads past the array's
  // `count` values or has more params than its stride (assimp indexes the
  // array unchecked).
  void check_lists(const std::string& name) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Measures `data` (a whole COLLADA document) and throws InputError naming
// `name` and the figure when check_lists() refuses, the depth or the node
// copies exceed the limits above, or a node is its own ancestor.
void check_collada_node_graph(const std::string& name, const char* data, std::size_t size);

// The same over a file read in pieces (plain or .gz: BufferedInput).
void check_collada_node_graph_of_file(const std::string& name, const std::filesystem::path& file);

}  // namespace cellbake

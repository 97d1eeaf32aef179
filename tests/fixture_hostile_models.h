// Generators of hostile model files for the reliability tests (issue #37):
// small files whose structure, not their size, would crash or exhaust an
// importer: node chains and nestings far deeper than any real model, glTF
// node graphs (glTF children, COLLADA instance_node) whose shared children
// multiply into billions of instance paths.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace cellbake::test {

// One triangle (0,0,0) (1,0,0) (0,1,0) as a glTF data-URI buffer.
inline const char* kGltfTriangleBuffer =
    "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA";

// A glTF 2.0 document with the one-triangle mesh 0, nodes `nodes_json` (the
// text of the "nodes" array) and one scene whose root is node 0.
inline std::string gltf_with_nodes(const std::string& nodes_json) {
  return std::string(R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[)") +
         nodes_json +
         R"(],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
         R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)"
         R"("bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36,"uri":")" +
         kGltfTriangleBuffer + "\"}]}";
}

// Nodes 0 .. levels-1 each listing node i+1 as its child `copies` times; the
// last node places the mesh: copies^levels instance paths (one chain when 1).
inline std::string gltf_node_chain(int levels, int copies = 1) {
  std::string nodes;
  for (int i = 0; i < levels; ++i) {
    nodes += R"({"children":[)";
    for (int c = 0; c < copies; ++c) nodes += (c ? "," : "") + std::to_string(i + 1);
    nodes += "]},";
  }
  nodes += R"({"mesh":0})";
  return gltf_with_nodes(nodes);
}

// The GLB container (header, JSON chunk padded with blanks) of glTF `json`.
inline std::string glb_of(std::string json) {
  while (json.size() % 4) json += ' ';
  const auto u32 = [](std::uint32_t v) {
    return std::string{char(v & 255), char(v >> 8 & 255), char(v >> 16 & 255), char(v >> 24 & 255)};
  };
  return "glTF" + u32(2) + u32(std::uint32_t(20 + json.size())) + u32(std::uint32_t(json.size())) + "JSON" +
         json;
}

// COLLADA 1.4 with one triangle (geometry "g"), the nodes `library_nodes`
// (the text inside <library_nodes>, none when empty) and the visual scene
// holding `scene_nodes`.
inline std::string collada_document(const std::string& library_nodes, const std::string& scene_nodes) {
  return std::string(
             R"(<?xml version="1.0"?><COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">)"
             R"(<asset><up_axis>Y_UP</up_axis></asset><library_geometries><geometry id="g"><mesh>)"
             R"(<source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array><technique_common>)"
             R"(<accessor source="#pa" count="3" stride="3"><param name="X" type="float"/><param name="Y" type="float"/>)"
             R"(<param name="Z" type="float"/></accessor></technique_common></source><vertices id="v">)"
             R"(<input semantic="POSITION" source="#p"/></vertices><triangles count="1">)"
             R"(<input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles></mesh></geometry>)"
             R"(</library_geometries>)") +
         (library_nodes.empty() ? "" : "<library_nodes>" + library_nodes + "</library_nodes>") +
         R"(<library_visual_scenes><visual_scene id="s">)" + scene_nodes +
         R"(</visual_scene></library_visual_scenes><scene><instance_visual_scene url="#s"/></scene></COLLADA>)";
}

// COLLADA with one triangle placed by a visual-scene node nested `depth` deep.
inline std::string collada_nested_nodes(int depth) {
  std::string nodes;
  for (int i = 0; i < depth; ++i) nodes += "<node>";
  nodes += R"(<instance_geometry url="#g"/>)";
  for (int i = 0; i < depth; ++i) nodes += "</node>";
  return collada_document("", nodes);
}

// COLLADA whose library nodes n0 .. n(levels-1) each instance node i+1
// `copies` times (<instance_node url="#n1"/>); the last places the triangle,
// and the visual scene instances n0: copies^levels instance paths, a chain
// `levels` long when 1. With `cycle`, the last node instances n0 too.
inline std::string collada_instance_nodes(int levels, int copies = 1, bool cycle = false) {
  std::string nodes;
  for (int i = 0; i < levels; ++i) {
    nodes += "<node id=\"n" + std::to_string(i) + "\">";
    for (int c = 0; c < copies; ++c) nodes += "<instance_node url=\"#n" + std::to_string(i + 1) + "\"/>";
    nodes += "</node>";
  }
  nodes += "<node id=\"n" + std::to_string(levels) + R"("><instance_geometry url="#g"/>)" +
           (cycle ? R"(<instance_node url="#n0"/>)" : "") + "</node>";
  return collada_document(nodes, R"(<node id="root"><instance_node url="#n0"/></node>)");
}

// X3D with one triangle inside `depth` nested Transforms.
inline std::string x3d_nested_transforms(int depth) {
  std::string s = R"(<?xml version="1.0"?><X3D profile="Interchange" version="3.3"><Scene>)";
  for (int i = 0; i < depth; ++i) s += "<Transform>";
  s +=
      R"(<Shape><IndexedFaceSet coordIndex="0 1 2 -1"><Coordinate point="0 0 0 1 0 0 0 1 0"/></IndexedFaceSet></Shape>)";
  for (int i = 0; i < depth; ++i) s += "</Transform>";
  return s + "</Scene></X3D>";
}

// A DirectX .x text file with one triangle inside `depth` nested Frames
// (assimp's .x parser recurses per Frame: 100,000 overflow its stack).
inline std::string directx_nested_frames(int depth) {
  std::string s = "xof 0303txt 0032\n";
  for (int i = 0; i < depth; ++i) s += "Frame F" + std::to_string(i) + " {\n";
  s += "Mesh { 3; 0.0;0.0;0.0;, 1.0;0.0;0.0;, 0.0;1.0;0.0;; 1; 3;0,1,2;; }\n";
  for (int i = 0; i < depth; ++i) s += "}\n";
  return s;
}

// The same Frames nested `depth` deep in the binary .x format (no mesh): its
// token stream is not scanned before import (pipeline/readers/
// directx_nesting.h), so 100,000 still overflow assimp's stack.
inline std::string directx_binary_nested_frames(int depth) {
  std::string s = "xof 0303bin 0032";
  const auto word = [&](std::uint16_t w) { s.push_back(char(w & 0xff)), s.push_back(char(w >> 8)); };
  const auto dword = [&](std::uint32_t d) {
    for (int i = 0; i < 4; ++i) s.push_back(char((d >> (8 * i)) & 0xff));
  };
  for (int i = 0; i < depth; ++i) {
    word(1), dword(5), s += "Frame";  // TOKEN_NAME "Frame"
    word(10);                          // TOKEN_OBRACE
  }
  for (int i = 0; i < depth; ++i) word(11);  // TOKEN_CBRACE
  return s;
}

}  // namespace cellbake::test

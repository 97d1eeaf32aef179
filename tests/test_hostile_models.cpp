// Hostile model files (issue #37): nestings and node graphs that crashed the
// importer (stack overflow) or never finished (2^30 instance paths) end in an
// InputError naming the file within seconds, before assimp imports them.
#include <gtest/gtest.h>
#include <zlib.h>

#include <chrono>
#include <string>

#include "pipeline/input_error.h"
#include "pipeline/readers/collada_node_graph.h"
#include "pipeline/readers/directx_nesting.h"
#include "pipeline/readers/gltf_node_graph.h"
#include "pipeline/readers/markup_nesting.h"
#include "pipeline/readers/model_reader.h"
#include "tests/fixture_hostile_models.h"
#include "tests/fixture_read_error.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using test::TempDir;
using test::write_text;

using test::read_error;

void write_gz(const std::filesystem::path& file, const std::string& text) {
  gzFile gz = gzopen(file.c_str(), "wb");
  ASSERT_NE(gz, nullptr);
  ASSERT_EQ(gzwrite(gz, text.data(), unsigned(text.size())), int(text.size()));
  gzclose(gz);
}

// Runs cellbake `args`; expects a clean error exit naming `name` with `words`, within 10 s.
void expect_named_error_quickly(const std::string& args, const std::string& name, const std::string& words) {
  const auto start = std::chrono::steady_clock::now();
  const test::CommandResult r = test::run_cellbake(args);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 1) << r.output;  // an error, not a signal (-1)
  EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(words), std::string::npos) << r.output;
  EXPECT_LT(seconds, 10.0);
}

TEST(HostileModels, GltfNodeChain100000DeepIsRefusedNamingTheFile) {
  TempDir dir;
  write_text(dir / "chain.gltf", test::gltf_node_chain(100000));
  const std::string file = (dir / "chain.gltf").string();
  expect_named_error_quickly("ingest " + file + " --store " + (dir / "s.db").string(), "chain.gltf",
                             "node hierarchy 100001 levels deep, more than 1024");
  EXPECT_FALSE(std::filesystem::exists(dir / "s.db"));
}

TEST(HostileModels, GlbAndGzippedGltfNodeChainsAreRefusedToo) {
  TempDir dir;
  write_text(dir / "chain.glb", test::glb_of(test::gltf_node_chain(100000)));
  write_gz(dir / "chain.gltf.gz", test::gltf_node_chain(100000));
  EXPECT_NE(read_error(dir / "chain.glb").find("chain.glb: node hierarchy 100001 levels deep"),
            std::string::npos);
  EXPECT_NE(read_error(dir / "chain.gltf.gz").find("chain.gltf.gz: node hierarchy 100001 levels deep"),
            std::string::npos);
}

TEST(HostileModels, GltfNodeChainsWithinTheLimitStillRead) {
  TempDir dir;
  write_text(dir / "chain.gltf", test::gltf_node_chain(1000));
  std::uint64_t triangles = 0;
  EXPECT_EQ(read_error(dir / "chain.gltf", &triangles), "");
  EXPECT_EQ(triangles, 1u);
}

TEST(HostileModels, GltfSharedChildren30LevelsAreCountedAndRefusedBeforeTheWalk) {
  TempDir dir;
  write_text(dir / "dag.gltf", test::gltf_node_chain(30, 2));  // 2^31 - 1 node copies, 2^30 placed meshes
  const auto start = std::chrono::steady_clock::now();
  const std::string error = read_error(dir / "dag.gltf");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
  EXPECT_NE(error.find("dag.gltf: node graph places 2147483647 node instances"), std::string::npos) << error;
  EXPECT_NE(error.find("more than 1000000"), std::string::npos) << error;
}

// Found by fuzz_gltf_reader: a byte of invalid UTF-8 in a string made the
// strict JSON parser give up while assimp's lenient one read the 2^30 paths.
TEST(HostileModels, InvalidUtf8InAStringDoesNotHideTheNodeGraph) {
  TempDir dir;
  std::string json = test::gltf_node_chain(30, 2);
  json.insert(json.find("octet-stream") + 5, "I\xC9\xD5\x9C");
  write_text(dir / "dag.gltf", json);
  const std::string error = read_error(dir / "dag.gltf");
  EXPECT_NE(error.find("dag.gltf: node graph places 2147483647 node instances"), std::string::npos) << error;
  write_text(dir / "broken.gltf", R"({"asset":{"version":"2.0"},"nodes":[{"children":[1]},)");
  EXPECT_NE(read_error(dir / "broken.gltf").find("broken.gltf:byte "), std::string::npos);
  EXPECT_NE(read_error(dir / "broken.gltf").find("not valid glTF JSON"), std::string::npos);
}

TEST(HostileModels, GltfSharedChildrenWithinTheLimitArePlacedOncePerPath) {
  TempDir dir;
  write_text(dir / "dag.gltf", test::gltf_node_chain(10, 2));
  std::uint64_t triangles = 0;
  EXPECT_EQ(read_error(dir / "dag.gltf", &triangles), "");
  EXPECT_EQ(triangles, 1024u);
}

TEST(HostileModels, GltfNodeCycleIsRefused) {
  TempDir dir;
  write_text(dir / "cycle.gltf",
             test::gltf_with_nodes(R"({"children":[1]},{"children":[2]},{"children":[1],"mesh":0})"));
  EXPECT_NE(read_error(dir / "cycle.gltf").find("cycle.gltf:node 1: is its own ancestor"), std::string::npos)
      << read_error(dir / "cycle.gltf");
}

TEST(HostileModels, ColladaNodesNested10000And100000DeepAreRefused) {
  TempDir dir;
  write_text(dir / "deep10k.dae", test::collada_nested_nodes(10000));
  write_text(dir / "deep100k.dae", test::collada_nested_nodes(100000));
  EXPECT_NE(read_error(dir / "deep10k.dae").find("deep10k.dae:byte "), std::string::npos);
  EXPECT_NE(read_error(dir / "deep10k.dae").find("XML nested deeper than 2048 levels"), std::string::npos);
  // `info` reads a model into a temporary store: the same refusal.
  expect_named_error_quickly("info " + (dir / "deep100k.dae").string(), "deep100k.dae",
                             "XML nested deeper than 2048 levels");
}

TEST(HostileModels, X3dTransformsNested100000DeepAreRefused) {
  TempDir dir;
  write_text(dir / "deep.x3d", test::x3d_nested_transforms(100000));
  write_gz(dir / "deep.x3d.gz", test::x3d_nested_transforms(100000));
  EXPECT_NE(read_error(dir / "deep.x3d").find("deep.x3d:byte "), std::string::npos);
  EXPECT_NE(read_error(dir / "deep.x3d").find("XML nested deeper than 2048 levels"), std::string::npos);
  EXPECT_NE(read_error(dir / "deep.x3d.gz").find("deep.x3d.gz:byte "), std::string::npos);
}

TEST(HostileModels, DirectXTextFramesNested100000DeepAreRefusedEvenInProcess) {
  TempDir dir;
  write_text(dir / "deep.x", test::directx_nested_frames(100000));
  write_gz(dir / "deep.x.gz", test::directx_nested_frames(100000));
  EXPECT_NE(read_error(dir / "deep.x").find("deep.x:byte "), std::string::npos);
  EXPECT_NE(read_error(dir / "deep.x").find("DirectX .x nested deeper than 2048 levels"), std::string::npos);
  EXPECT_NE(read_error(dir / "deep.x.gz").find("deep.x.gz:byte "), std::string::npos);
  // Refused before import, so assimp never runs, not even in cellbake's own process.
  expect_named_error_quickly("ingest " + (dir / "deep.x").string() + " --import-in-process --store " +
                                 (dir / "s.db").string(),
                             "deep.x:byte ", "DirectX .x nested deeper than 2048 levels");
  EXPECT_FALSE(std::filesystem::exists(dir / "s.db"));
  // 1,000 deep reads.
  write_text(dir / "ok.x", test::directx_nested_frames(1000));
  std::uint64_t triangles = 0;
  EXPECT_EQ(read_error(dir / "ok.x", &triangles), "");
  EXPECT_EQ(triangles, 1u);
}

TEST(DirectXNesting, CountsTextBracesOutsideStringsAndCommentsAndLeavesBinaryAlone) {
  const auto depth = [](const std::string& bytes, std::size_t piece) {
    DirectXNestingScan scan;
    for (std::size_t at = 0; at < bytes.size(); at += piece)
      scan.feed(bytes.data() + at, std::min(piece, bytes.size() - at));
    return scan.max_depth();
  };
  const std::string text = "xof 0303txt 0032\n// {{{{ comment\n# {{{{ also\nFrame a { \"{{{{\" Frame b { } }\n";
  for (std::size_t piece : {std::size_t{1}, std::size_t{5}, text.size()}) EXPECT_EQ(depth(text, piece), 2) << piece;
  EXPECT_EQ(depth("xof 0303bin 0032{{{{{{", 3), 0);  // binary tokens: not scanned
  EXPECT_EQ(depth("not a .x file {{{{", 4), 0);
  const std::string deep = test::directx_nested_frames(3000);
  EXPECT_THROW(check_directx_nesting("deep.x", deep.data(), deep.size()), InputError);
  const std::string ok = test::directx_nested_frames(2047);  // and the Mesh inside: 2048 levels
  EXPECT_NO_THROW(check_directx_nesting("ok.x", ok.data(), ok.size()));
}

TEST(HostileModels, ColladaAndX3dNestedWithinTheLimitsRead) {
  TempDir dir;
  write_text(dir / "deep.dae", test::collada_nested_nodes(1000));
  write_text(dir / "deep.x3d", test::x3d_nested_transforms(1000));
  for (const char* name : {"deep.dae", "deep.x3d"}) {
    std::uint64_t triangles = 0;
    EXPECT_EQ(read_error(dir / name, &triangles), "") << name;
    EXPECT_EQ(triangles, 1u) << name;
  }
}

TEST(HostileModels, ColladaSharedInstanceNodes30LevelsAreCountedAndRefusedBeforeImport) {
  TempDir dir;
  write_text(dir / "shared.dae", test::collada_instance_nodes(30, 2));
  expect_named_error_quickly("ingest " + (dir / "shared.dae").string() + " --store " + (dir / "s.db").string(),
                             "shared.dae",
                             "node graph places 2147483649 node instances (a node placed by several "
                             "instance_node references is copied per path), more than 1000000");
  EXPECT_FALSE(std::filesystem::exists(dir / "s.db"));
}

TEST(HostileModels, ColladaInstanceNodeChainsAndCyclesAreRefused) {
  TempDir dir;
  // A flat file (no XML nesting to speak of) whose references chain 100,000 nodes deep.
  write_text(dir / "chain.dae", test::collada_instance_nodes(100000));
  write_gz(dir / "chain.dae.gz", test::collada_instance_nodes(100000));
  write_text(dir / "cycle.dae", test::collada_instance_nodes(3, 1, true));
  // "#" names what has no name: the visual scene itself (found by fuzz_collada_reader: assimp recursed until the stack ran out).
  write_text(dir / "empty_url.dae", test::collada_document("", R"(<node id="r"><instance_node url="#"/></node>)"));
  EXPECT_NE(read_error(dir / "chain.dae").find("chain.dae: node hierarchy 100003 levels deep (instance_node "
                                               "included), more than 1024"),
            std::string::npos)
      << read_error(dir / "chain.dae");
  EXPECT_NE(read_error(dir / "chain.dae.gz").find("chain.dae.gz: node hierarchy 100003 levels deep"),
            std::string::npos);
  EXPECT_NE(read_error(dir / "cycle.dae").find("cycle.dae:node 'n0': is its own ancestor"), std::string::npos)
      << read_error(dir / "cycle.dae");
  EXPECT_NE(read_error(dir / "empty_url.dae").find("empty_url.dae:node 's': is its own ancestor"), std::string::npos)
      << read_error(dir / "empty_url.dae");
}

TEST(HostileModels, ColladaSharedInstanceNodesWithinTheLimitArePlacedOncePerPath) {
  TempDir dir;
  write_text(dir / "shared.dae", test::collada_instance_nodes(4, 2));
  write_text(dir / "chain.dae", test::collada_instance_nodes(1000));
  std::uint64_t triangles = 0;
  EXPECT_EQ(read_error(dir / "shared.dae", &triangles), "");
  EXPECT_EQ(triangles, 16u);  // 2^4 paths, as counted
  EXPECT_EQ(read_error(dir / "chain.dae", &triangles), "");
  EXPECT_EQ(triangles, 1u);
}

TEST(HostileModels, ColladaIndexListsAndCountsAssimpWouldLoopOrReserveOnAreRefused) {
  TempDir dir;
  const std::string good = test::collada_nested_nodes(1);
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  // "<p># 1 2</p>": assimp's index loop never passes the '#' and grew its list to GBs (found by fuzz_collada_reader).
  write_text(dir / "hash.dae", with("<p>0 1 2</p>", "<p># 1 2</p>"));
  write_text(dir / "float.dae", with("<p>0 1 2</p>", "<p>0 1.5 2</p>"));
  write_text(dir / "floats.dae", with(R"(count="9")", R"(count="1000000000")"));
  write_text(dir / "triangles.dae", with(R"(<triangles count="1">)", R"(<triangles count="99999999999">)"));
  write_text(dir / "vcount.dae",
             with(R"(<triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>)",
                  R"(<polylist count="1"><input semantic="VERTEX" source="#v" offset="0"/>)"
                  R"(<vcount>3000000000</vcount><p>0 1 2</p></polylist>)"));
  EXPECT_NE(read_error(dir / "hash.dae").find("hash.dae:byte "), std::string::npos) << read_error(dir / "hash.dae");
  EXPECT_NE(read_error(dir / "hash.dae").find("<p> holds '#', not an index"), std::string::npos);
  EXPECT_NE(read_error(dir / "float.dae").find("<p> holds '.', not an index"), std::string::npos);
  EXPECT_NE(read_error(dir / "floats.dae").find("<float_array count=\"1000000000\">: more than the file's"),
            std::string::npos)
      << read_error(dir / "floats.dae");
  EXPECT_NE(read_error(dir / "triangles.dae").find("<triangles count=\"99999999999\">: more than the file's"),
            std::string::npos);
  EXPECT_NE(read_error(dir / "vcount.dae").find("a <vcount> sums to 3000000000 corners"), std::string::npos)
      << read_error(dir / "vcount.dae");
  // Blanks of every kind between the numbers: the file reads.
  std::uint64_t triangles = 0;
  write_text(dir / "blank.dae", with("<p>0 1 2</p>", "<p>\n 0\t1\r\n2 </p>"));
  EXPECT_EQ(read_error(dir / "blank.dae", &triangles), "");
  EXPECT_EQ(triangles, 1u);
}

TEST(ColladaNodeGraph, CountsDepthAndInstancesThroughNestingAndReferences) {
  const auto measure = [](const std::string& text, std::size_t piece) {
    ColladaNodeScan scan;
    for (std::size_t at = 0; at < text.size(); at += piece)
      scan.feed(text.data() + at, std::min(piece, text.size() - at));
    return scan.measure("m.dae");
  };
  for (const std::size_t piece : {std::size_t{1}, std::size_t{7}, std::size_t{1} << 20}) {
    SCOPED_TRACE(piece);
    // The visual scene -> root -> n0 -> 2 x n1 -> 2 x n2 (places the mesh): 1 + 1 + 1 + 2 + 4 nodes, 5 deep.
    const ColladaNodeGraph shared = measure(test::collada_instance_nodes(2, 2), piece);
    EXPECT_EQ(shared.depth, 5);
    EXPECT_EQ(shared.node_instances, 9u);
    const ColladaNodeGraph nested = measure(test::collada_nested_nodes(5), piece);
    EXPECT_EQ(nested.depth, 6);
    EXPECT_EQ(nested.node_instances, 6u);
    // References and ids inside comments, CDATA and attribute values are not nodes.
    const ColladaNodeGraph hidden = measure(
        test::collada_document(R"(<node id="a"><!-- <node id="x"> --><![CDATA[<node>]]></node>)",
                               R"(<node note="<node>"><instance_node url="#a"/><instance_node url="#a"/>)"
                               R"(<instance_node url="#missing"/></node>)"),
        piece);
    EXPECT_EQ(hidden.depth, 3);
    EXPECT_EQ(hidden.node_instances, 4u);
    // Scene nodes resolve by name too; a library node by id only, as assimp looks them up.
    const ColladaNodeGraph named = measure(
        test::collada_document(R"(<node name="lib"/>)", R"(<node name="b"/><node><instance_node url="#b"/>)"
                                                        R"(<instance_node url="#lib"/></node>)"),
        piece);
    EXPECT_EQ(named.depth, 3);
    EXPECT_EQ(named.node_instances, 4u);
  }
}

// The depth of `text` as MarkupNestingScan counts it, fed in pieces of `piece` bytes.
int depth_of(const std::string& text, std::size_t piece = 1) {
  MarkupNestingScan scan;
  for (std::size_t at = 0; at < text.size(); at += piece)
    scan.feed(text.data() + at, std::min(piece, text.size() - at));
  return scan.max_depth();
}

TEST(MarkupNesting, CountsXmlElementsOutsideCommentsCdataInstructionsAndAttributeValues) {
  const std::string xml =
      "\xEF\xBB\xBF <?xml version=\"1.0\"?><!DOCTYPE a [<!ENTITY e \"<b><b>\">]>"
      "<a x=\"<b>\" y='/>'><!-- <b><b><b> --><![CDATA[<b><b><b>]]><c/><d><e></e></d></a>";
  for (std::size_t piece : {std::size_t{1}, std::size_t{7}, xml.size()})
    EXPECT_EQ(depth_of(xml, piece), 3) << piece;
  EXPECT_EQ(depth_of("<a><b/><b/><b></b></a>"), 2);
}

TEST(MarkupNesting, CountsJsonBracketsOutsideStrings) {
  EXPECT_EQ(depth_of(R"( {"a":[1,{"b":"[[[{{{\"]]]"}],"c":{}})"), 3);
  EXPECT_EQ(depth_of("plain text [[[["), 0);  // neither JSON nor XML: not counted
  std::string deep(5000, '[');
  EXPECT_THROW(check_markup_nesting("deep.json", deep.data(), deep.size()), InputError);
  deep = std::string(2048, '[') + std::string(2048, ']');
  EXPECT_NO_THROW(check_markup_nesting("ok.json", deep.data(), deep.size()));
}

TEST(GltfNodeGraph, CountsDepthInstancesAndTrianglesWithMultiplicity) {
  // Root 0 lists 1 three times; 1 lists 2 twice; 2 places the one-triangle mesh: 1 + 3 * (1 + 2) node copies.
  const std::string json = test::gltf_with_nodes(R"({"children":[1,1,1]},{"children":[2,2]},{"mesh":0})");
  const GltfNodeGraph graph = measure_gltf_node_graph("g.gltf", json.data(), json.size());
  EXPECT_EQ(graph.depth, 3);
  EXPECT_EQ(graph.node_instances, 10u);
  EXPECT_EQ(graph.placed_triangles, 6u);
  const std::string huge = test::gltf_node_chain(70, 2);  // 2^70 paths: saturates
  const GltfNodeGraph saturated = measure_gltf_node_graph("h.gltf", huge.data(), huge.size());
  EXPECT_EQ(saturated.node_instances, std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(saturated.placed_triangles, std::numeric_limits<std::uint64_t>::max());
  EXPECT_NE(
      glb_json_chunk(reinterpret_cast<const unsigned char*>(test::glb_of(json).data()), json.size() + 24)
          .second,
      0u);
}

}  // namespace
}  // namespace cellbake

// `cellbake export` (issue #38): the GLB container read back, quantisation
// within its bounds, depth meshes refined to plain texture coordinates, a
// baked cell's triangles and images in the file, compression that decodes to
// the same streams, errors naming the missing cell and store; and, where Node
// and Chromium are installed (scripts/install-node-tools.sh), the Khronos
// validator's verdict and a three.js render against `cellbake render`.
// Three 64-pixel bakes of a small room (one cell each), a few seconds in all.
#include <gtest/gtest.h>

#include <meshoptimizer.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "pipeline/export/affine_face_mesh.h"
#include "pipeline/export/cell_gltf_export.h"
#include "pipeline/export/glb_builder.h"
#include "pipeline/export/gltf_vertex_streams.h"
#include "stages/chunk_lod.h"
#include "stages/encode/encode.h"
#include "storage/cell_db.h"
#include "storage/chunk_codec.h"
#include "storage/geometry_store.h"
#include "fixture_room_obj.h"
#include "fixture_textured.h"
#include "test_support.h"

namespace cellbake {
namespace {

using nlohmann::json;

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

// The bytes of buffer view `view` of a parsed file (uncompressed views only).
std::span<const std::uint8_t> view_bytes(const ParsedGlb& glb, int view) {
  const json& v = glb.json["bufferViews"][view];
  return std::span<const std::uint8_t>(glb.bin).subspan(v.value("byteOffset", 0), v["byteLength"].get<std::size_t>());
}

// The bytes of an accessor's elements (uncompressed, `element` bytes apart):
// its view from the accessor's offset on (views are shared by accessors).
std::span<const std::uint8_t> accessor_bytes(const ParsedGlb& glb, const json& accessor, std::size_t element) {
  return view_bytes(glb, accessor["bufferView"])
      .subspan(accessor.value("byteOffset", std::size_t{0}), accessor["count"].get<std::size_t>() * element);
}

// ------------------------------------------------------------------ container

TEST(GlbBuilder, RoundTripsChunksViewsAndAlignment) {
  GlbBuilder b;
  const std::vector<std::uint8_t> three{1, 2, 3}, five{4, 5, 6, 7, 8};
  EXPECT_EQ(b.add_buffer_view(three), 0);
  EXPECT_EQ(b.add_buffer_view(five, 4, gltf::kArrayBuffer), 1);
  b.add_accessor(1, gltf::kUnsignedByte, true, 1, "VEC4", {4, 5, 6, 7}, {4, 5, 6, 7});
  b.json()["extras"] = {{"note", "a string long enough to need padding!"}};
  const std::vector<std::uint8_t> bytes = b.finish();
  ASSERT_EQ(bytes.size() % 4, 0u);
  const ParsedGlb glb = parse_glb(bytes);
  EXPECT_EQ(glb.version, 2u);
  EXPECT_EQ(glb.json["asset"]["version"], "2.0");
  EXPECT_EQ(glb.json["extras"]["note"], "a string long enough to need padding!");
  ASSERT_EQ(glb.bin.size(), 12u);  // 3 bytes, padded to 4, then 5 padded to 8
  EXPECT_EQ(glb.json["buffers"][0]["byteLength"], 12);
  EXPECT_EQ(glb.json["bufferViews"][1]["byteOffset"], 4);
  EXPECT_EQ(glb.json["bufferViews"][1]["byteStride"], 4);
  const auto second = view_bytes(glb, 1);
  EXPECT_EQ(std::vector<std::uint8_t>(second.begin(), second.end()), five);
  EXPECT_EQ(glb.json["accessors"][0]["min"], json({4, 5, 6, 7}));
  // The JSON chunk is padded with spaces, the BIN chunk with zeros.
  const std::uint32_t json_length = bytes[12] | bytes[13] << 8 | bytes[14] << 16 | bytes[15] << 24;
  EXPECT_EQ(json_length % 4, 0u);
  EXPECT_EQ(glb.bin[3], 0);
}

TEST(GlbBuilder, ParseNamesWhatIsWrong) {
  GlbBuilder b;
  b.add_buffer_view(std::vector<std::uint8_t>{1, 2, 3, 4});
  const std::vector<std::uint8_t> good = b.finish();
  const auto fails_with = [](std::vector<std::uint8_t> bytes, const std::string& what) {
    try {
      parse_glb(bytes);
      ADD_FAILURE() << "accepted: expected " << what;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  std::vector<std::uint8_t> bad = good;
  bad[0] = 'x';
  fails_with(bad, "magic");
  bad = good;
  bad[4] = 1;
  fails_with(bad, "version 1");
  fails_with(std::vector<std::uint8_t>(good.begin(), good.end() - 4), "header length");
  bad = good;
  bad[16] = 'X';  // the first chunk's type
  fails_with(bad, "not JSON");
  fails_with(std::vector<std::uint8_t>(good.begin(), good.begin() + 10), "too short");
}

// ------------------------------------------------------------- vertex streams

TEST(VertexStreams, QuantisedPositionsStayWithinTheBound) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-3, 17), y(100, 100.5), z(-1e3, -990);
  std::vector<Vec3d> points;
  Box3d bounds;
  for (int i = 0; i < 2000; ++i) {
    points.push_back({x(rng), y(rng), z(rng)});
    bounds.expand(points.back());
  }
  const PositionQuantization pq = position_quantization(bounds);
  EXPECT_DOUBLE_EQ(pq.scale, bounds.extent().x / 2);  // the widest half extent
  const std::vector<std::int16_t> q16 = quantize_positions(points, pq);
  const double bound = position_error_bound(pq);
  double worst = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(q16[4 * i + 3], 0);
    for (int a = 0; a < 3; ++a) {
      // As a viewer dequantises: float node transform times the normalised value.
      const float normalised = std::max(q16[4 * i + a] / 32767.0f, -1.0f);
      const double back = float(pq.translation[a]) + float(pq.scale) * normalised;
      worst = std::max(worst, std::abs(back - points[i][a]));
    }
  }
  EXPECT_LE(worst, bound);
  EXPECT_GT(worst, bound / 4);  // the bound is not loose by orders of magnitude
  EXPECT_THROW(quantize_positions(std::vector<Vec3d>{{18, 100, -995}}, pq), std::invalid_argument);
  // At 12 bits the values lie within +-2047 and the bound is 16 times looser.
  const PositionQuantization p12 = position_quantization(bounds, 12);
  const std::vector<std::int16_t> q12 = quantize_positions(points, p12);
  double worst12 = 0;
  int largest = 0;
  for (std::size_t i = 0; i < points.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      largest = std::max(largest, std::abs(int(q12[4 * i + a])));
      worst12 = std::max(worst12, std::abs(p12.translation[a] + p12.scale * q12[4 * i + a] / 32767.0 - points[i][a]));
    }
  EXPECT_EQ(largest, 2047);  // the widest axis reaches the end of the range
  EXPECT_LE(worst12, position_error_bound(p12));
  EXPECT_GT(worst12, bound * 4);
}

TEST(VertexStreams, PositionBitsAreTheFewestWithinTheTolerance) {
  const Box3d box{{-10, 0, 0}, {10, 1, 1}};  // half extent 10
  for (double tolerance : {1e-3, 4e-3, 0.05}) {
    const int bits = position_bits_within(box, tolerance);
    EXPECT_LE(position_error_bound(position_quantization(box, bits)), tolerance) << tolerance;
    if (bits > 8) {
      EXPECT_GT(position_error_bound(position_quantization(box, bits - 1)), tolerance) << tolerance;
    }
  }
  // 10 / (2^(bits-1) - 1) / 2 <= 1e-3 first at 14 bits (8191 steps: 0.61 mm).
  EXPECT_EQ(position_bits_within(box, 1e-3), 14);
  EXPECT_EQ(position_bits_within(box, 1e-9), 16);  // none is within: all bits
  EXPECT_EQ(position_bits_within(box, 0), 16);
  EXPECT_EQ(position_bits_within(box, 100), 8);
}

TEST(VertexStreams, NormalsUvsAndColoursWithinHalfAStep) {
  const std::vector<Vec3f> normals{{0, 0, 1}, {-1, 0, 0}, {0.6f, -0.8f, 0}, {0.57735f, 0.57735f, 0.57735f}};
  const std::vector<std::int8_t> n8 = quantize_normals(normals);
  for (std::size_t i = 0; i < normals.size(); ++i) {
    EXPECT_NEAR(n8[4 * i] / 127.0, normals[i].x, 0.5 / 127 + 1e-6);
    EXPECT_NEAR(n8[4 * i + 1] / 127.0, normals[i].y, 0.5 / 127 + 1e-6);
    EXPECT_NEAR(n8[4 * i + 2] / 127.0, normals[i].z, 0.5 / 127 + 1e-6);
  }
  const std::vector<Uv> uvs{{0, 1}, {0.25f, 0.7f}, {1, 0}};
  ASSERT_TRUE(uvs_in_unit_square(uvs));
  EXPECT_FALSE(uvs_in_unit_square(std::vector<Uv>{{1.5f, 0}}));
  const std::vector<std::uint16_t> u16 = quantize_uvs(uvs);
  for (std::size_t i = 0; i < uvs.size(); ++i) {
    EXPECT_NEAR(u16[2 * i] / 65535.0, uvs[i].u, 0.5 / 65535 + 1e-7);
    EXPECT_NEAR(u16[2 * i + 1] / 65535.0, uvs[i].v, 0.5 / 65535 + 1e-7);
  }
  // sRGB 0, 128, 255 -> linear 0, 0.2158605, 1; alpha as it is.
  const std::vector<std::uint16_t> c = linear_colors(std::vector<Rgba8>{{0, 128, 255, 128}});
  EXPECT_EQ(c[0], 0);
  EXPECT_NEAR(c[1] / 65535.0, 0.2158605, 1e-5);
  EXPECT_EQ(c[2], 65535);
  EXPECT_EQ(c[3], 128 * 257);
  const std::vector<std::uint8_t> c8 = linear_colors8(std::vector<Rgba8>{{0, 128, 255, 128}});
  EXPECT_EQ(c8, std::vector<std::uint8_t>({0, 55, 255, 128}));  // 0.2158605 * 255 = 55.04
}

// ------------------------------------------------------- affine depth meshes

TEST(AffineFaceMesh, EdgeErrorIsTheLargestProjectiveGap) {
  // Along an edge from depth qa to qb, the projective parameter of the point
  // at linear parameter t is s = qb t / (qa (1 - t) + qb t).
  for (const auto& [qa, qb] : std::vector<std::pair<double, double>>{{1, 4}, {3, 2}, {1, 30}, {5, 5}}) {
    double gap = 0;
    for (int i = 0; i <= 10000; ++i) {
      const double t = i / 10000.0;
      gap = std::max(gap, std::abs(qb * t / (qa * (1 - t) + qb * t) - t));
    }
    EXPECT_NEAR(affine_uv_edge_error_px(qa, qb, 100), 100 * gap, 1e-4) << qa << " " << qb;
  }
  EXPECT_EQ(affine_uv_edge_error_px(2, 2, 500), 0);
}

// A floor seen from 1.6 m above in the +X face of a 256-pixel sample: depths
// from 2 to 40 m across two large triangles.
FaceMesh slanted_floor() {
  FaceMesh m;
  const FaceBasis b = cube_face_basis(0);
  for (const auto& [s, t, depth] : std::vector<std::array<double, 3>>{{-0.8, -0.8, 2}, {0.8, -0.8, 2}, {0.04, -0.04, 40}, {-0.04, -0.04, 40}}) {
    const Vec3d p = cube_face_direction(b, s, t) * depth;
    m.positions.push_back({float(p.x), float(p.y), float(p.z)});
    m.uvs.push_back({float((s + 1) / 2), float((1 - t) / 2)});
  }
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

TEST(AffineFaceMesh, RefinementMeetsTheToleranceWithoutCracks) {
  const FaceMesh floor = slanted_floor();
  const AffineRefinement r = refine_for_affine_uvs(floor, 0, 256, 256, 0.5);
  EXPECT_GT(r.edges_split, 10u);
  EXPECT_LE(r.max_edge_error_px, 0.5);
  // Inside every triangle too, the linear texture coordinates stay within a
  // pixel of the projection of the point (its sample ray's texel).
  const FaceBasis b = cube_face_basis(0);
  double worst = 0;
  const auto to_d = [](const Vec3f& p) { return Vec3d{p.x, p.y, p.z}; };
  for (std::size_t t = 0; t < r.mesh.triangle_count(); ++t)
    for (double w0 : {0.2, 1.0 / 3, 0.6})
      for (double w1 : {0.2, 0.3}) {
        const double w2 = 1 - w0 - w1;
        if (w2 < 0) continue;
        const std::uint32_t i0 = r.mesh.indices[3 * t], i1 = r.mesh.indices[3 * t + 1], i2 = r.mesh.indices[3 * t + 2];
        const Vec3d p = to_d(r.mesh.positions[i0]) * w0 + to_d(r.mesh.positions[i1]) * w1 + to_d(r.mesh.positions[i2]) * w2;
        const double u = r.mesh.uvs[i0].u * w0 + r.mesh.uvs[i1].u * w1 + r.mesh.uvs[i2].u * w2;
        const double v = r.mesh.uvs[i0].v * w0 + r.mesh.uvs[i1].v * w1 + r.mesh.uvs[i2].v * w2;
        const double depth = dot(p, b.forward);
        const double s = dot(p, b.right) / depth, tt = dot(p, b.up) / depth;
        worst = std::max(worst, std::hypot((u - (s + 1) / 2) * 256, (v - (1 - tt) / 2) * 256));
      }
  EXPECT_LT(worst, 1.0);
  // Unrefined, the same floor is off by tens of pixels.
  EXPECT_GT(affine_uv_edge_error_px(2, 40, 0.76 * 256 * std::sqrt(2.0)), 50);
  // No T-junctions: every edge is shared by two triangles in opposite
  // directions, or lies on the quad's outline (a split of one of its 4 edges).
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
  for (std::size_t t = 0; t < r.mesh.triangle_count(); ++t)
    for (int e = 0; e < 3; ++e) ++directed[{r.mesh.indices[3 * t + e], r.mesh.indices[3 * t + (e + 1) % 3]}];
  const auto on_outline = [&](std::uint32_t a, std::uint32_t c) {
    const Uv& ua = r.mesh.uvs[a];
    const Uv& uc = r.mesh.uvs[c];
    for (int e = 0; e < 4; ++e) {
      const Uv& p = floor.uvs[std::size_t(e)];
      const Uv& q2 = floor.uvs[std::size_t((e + 1) % 4)];
      const auto cross2 = [&](const Uv& x) { return (q2.u - p.u) * (x.v - p.v) - (q2.v - p.v) * (x.u - p.u); };
      if (std::abs(cross2(ua)) < 1e-6 && std::abs(cross2(uc)) < 1e-6) return true;
    }
    return false;
  };
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    if (!directed.contains({edge.second, edge.first})) {
      EXPECT_TRUE(on_outline(edge.first, edge.second));
    }
  }
  // The area in texture space is kept: the refinement only subdivides.
  const auto uv_area = [](const FaceMesh& m) {
    double a = 0;
    for (std::size_t t = 0; t < m.triangle_count(); ++t) {
      const Uv& p = m.uvs[m.indices[3 * t]];
      const Uv& q1 = m.uvs[m.indices[3 * t + 1]];
      const Uv& q2 = m.uvs[m.indices[3 * t + 2]];
      a += ((q1.u - p.u) * (q2.v - p.v) - (q1.v - p.v) * (q2.u - p.u)) / 2;
    }
    return a;
  };
  EXPECT_NEAR(uv_area(r.mesh), uv_area(floor), 1e-6);
}

// ------------------------------------------------------------- baked cells

// Bakes of the pillar room from one store, one 2 m cell each at (2, 6, 1.6),
// 64-pixel faces, each made when a test first asks for it (CTest runs every
// test in a process of its own): "tdm" draws depth meshes only with PNG
// faces, "tdm_avif" the same with AVIF faces (the bake's default format),
// "geometry" its far field as exact geometry (the cheapest choice in this
// small room).
struct BakedCells {
  test::TempDir dir;
  BakeConfig base;
  std::filesystem::path store;
  std::map<std::string, std::filesystem::path> done;
  BakedCells() {
    base = test::obj_room_bake_config(dir.path(), test::pillar_room_obj(), Box3d{{1, 5, 1.6}, {3, 7, 1.6}}, 300, 64);
    base.far_choice = "tdm";
    store = base.store;
  }
  const std::filesystem::path& db(const std::string& name) {
    if (auto it = done.find(name); it != done.end()) return it->second;
    BakeConfig c = base;
    if (name == "tdm_avif") c.image_format = "avif";
    if (name == "geometry") c.far_choice = "cheapest";
    c.database = dir / (name + ".db");
    EXPECT_EQ(test::bake_quietly(c).cells_baked, 1u) << name;
    return done[name] = c.database;
  }
};

BakedCells& baked() {
  static BakedCells cells;
  return cells;
}

struct Exported {
  std::vector<std::uint8_t> bytes;
  GltfExportStats stats;
  CellRow row;
  DecodedCell cell;
};

Exported export_cell(const std::filesystem::path& db_path, bool compress, GltfExportOptions options = {}) {
  const CellDb db(db_path, CellDb::Mode::read_only);
  const GeometryStore store(baked().store);
  Exported e;
  e.row = *db.get_cell(1, true);
  e.cell = decode_cell(e.row, &store);
  options.compress = compress;
  GltfSceneContext context;
  context.lights = shading_lights(ShadingParams{}, context.up);
  context.database_name = db_path.filename().string();
  e.bytes = export_cells_glb({{&e.row, &e.cell}}, store, context, options, &e.stats);
  return e;
}

// Node indices under node `n` (itself included) whose name starts with `prefix`.
void collect(const json& doc, int n, const std::string& prefix, std::vector<int>& out) {
  const json& node = doc["nodes"][n];
  if (node.value("name", "").rfind(prefix, 0) == 0) out.push_back(n);
  if (node.contains("children"))
    for (int c : node["children"]) collect(doc, c, prefix, out);
}

int child_named(const json& doc, int parent, const std::string& name) {
  for (int c : doc["nodes"][parent]["children"])
    if (doc["nodes"][c]["name"] == name) return c;
  return -1;
}

// The chunk nodes under cell node `cell_node`'s "near field" group (none without one).
std::vector<int> near_chunk_nodes(const json& doc, int cell_node) {
  std::vector<int> nodes;
  const int near = child_named(doc, cell_node, "near field");
  if (near >= 0) collect(doc, near, "chunk ", nodes);
  return nodes;
}

TEST(Export, CellGlbHoldsTheCellsTrianglesWithinTheirBounds) {
  const Exported e = export_cell(baked().db("geometry"), false);
  ASSERT_FALSE(e.cell.far_pieces.empty() && e.cell.far_whole_ids.empty());
  const ParsedGlb glb = parse_glb(e.bytes);
  const json& doc = glb.json;
  EXPECT_EQ(doc["extensionsRequired"], json({"KHR_mesh_quantization"}));
  const int root = doc["scenes"][0]["nodes"][0];
  const json& info = doc["nodes"][root]["extras"]["cellbake"];
  const Vec3d origin{info["origin"][0], info["origin"][1], info["origin"][2]};
  EXPECT_EQ(origin, e.cell.bounds.center());
  EXPECT_EQ(info["up"], "z");
  const int cell_node = doc["nodes"][root]["children"][0];
  const json& cell = doc["nodes"][cell_node]["extras"]["cellbake"];
  EXPECT_EQ(cell["cell_id"], 1);
  EXPECT_EQ(cell["bounds"]["min"], json({e.cell.bounds.lo.x, e.cell.bounds.lo.y, e.cell.bounds.lo.z}));
  EXPECT_LE(e.cell.bounds.lo.x, 2.0);
  EXPECT_GE(e.cell.bounds.hi.x, 2.0);
  EXPECT_EQ(cell["samples"].size(), e.cell.samples.size());
  EXPECT_EQ(cell["samples"][0]["eye"][0], e.cell.samples[0].eye.x);

  // Every near chunk of the cell is a node whose mesh holds the chunk's
  // triangles, its dequantised positions within the chunk's bounds.
  const GeometryStore store(baked().store);
  ASSERT_FALSE(e.cell.near_ids.empty());
  const std::vector<int> chunk_nodes = near_chunk_nodes(doc, cell_node);
  ASSERT_EQ(chunk_nodes.size(), e.cell.near_ids.size());
  std::uint64_t triangles = 0;
  for (std::size_t k = 0; k < chunk_nodes.size(); ++k) {
    const json& node = doc["nodes"][chunk_nodes[k]];
    const auto chunk = store.load(e.cell.near_ids[k]);
    EXPECT_EQ(node["name"], "chunk " + std::to_string(e.cell.near_ids[k]));
    const double scale = node["scale"][0];
    const Vec3d t{node["translation"][0], node["translation"][1], node["translation"][2]};
    const double slack = position_error_bound({t, scale}) + 1e-9;
    std::size_t chunk_triangles = 0;
    for (const json& p : doc["meshes"][node["mesh"].get<int>()]["primitives"]) {
      const json& pos = doc["accessors"][p["attributes"]["POSITION"].get<int>()];
      const json& idx = doc["accessors"][p["indices"].get<int>()];
      EXPECT_EQ(pos["componentType"], gltf::kShort);
      EXPECT_TRUE(pos["normalized"].get<bool>());
      EXPECT_EQ(idx["count"].get<std::size_t>() % 3, 0u);
      chunk_triangles += idx["count"].get<std::size_t>() / 3;
      const json& colour = doc["accessors"][p["attributes"]["COLOR_0"].get<int>()];
      EXPECT_EQ(colour["count"], pos["count"]);
      EXPECT_EQ(colour["componentType"], gltf::kUnsignedByte);  // 8-bit linear, the default
      EXPECT_FALSE(p["attributes"].contains("NORMAL"));  // unlit: normals only when asked for
      // min / max are those of the data, and the data lies in the chunk's bounds.
      const auto data = accessor_bytes(glb, pos, 8);
      const std::size_t n = pos["count"];
      ASSERT_EQ(data.size(), n * 8);
      std::array<int, 3> lo{32767, 32767, 32767}, hi{-32767, -32767, -32767};
      for (std::size_t i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
          std::int16_t v;
          std::memcpy(&v, data.data() + 8 * i + 2 * a, 2);
          lo[a] = std::min<int>(lo[a], v), hi[a] = std::max<int>(hi[a], v);
          const double world = origin[a] + t[a] + scale * v / 32767.0;
          EXPECT_GE(world, chunk->bounds.lo[a] - slack);
          EXPECT_LE(world, chunk->bounds.hi[a] + slack);
        }
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(pos["min"][a], lo[a]);
        EXPECT_EQ(pos["max"][a], hi[a]);
      }
    }
    EXPECT_EQ(chunk_triangles, chunk->triangle_count());
    triangles += chunk_triangles;
  }
  EXPECT_EQ(triangles, e.stats.near_triangles);
  // The far geometry: as many triangles as the cell's row holds (pieces cut
  // out of store chunks; here no chunk is also in the near field).
  const int far = child_named(doc, cell_node, "far geometry");
  ASSERT_GE(far, 0);
  std::vector<int> far_nodes;
  collect(doc, far, "chunk ", far_nodes);
  EXPECT_EQ(far_nodes.size(), e.cell.far_pieces.size() + e.cell.far_whole_ids.size());
  std::uint64_t far_triangles = 0;
  for (int n : far_nodes)
    for (const json& p : doc["meshes"][doc["nodes"][n]["mesh"].get<int>()]["primitives"])
      far_triangles += doc["accessors"][p["indices"].get<int>()]["count"].get<std::uint64_t>() / 3;
  EXPECT_EQ(far_triangles, e.cell.far_geometry_triangles);
  EXPECT_EQ(e.stats.far_geometry_triangles, e.cell.far_geometry_triangles);
  EXPECT_EQ(e.stats.bytes, e.bytes.size());
}

// Chunk positions take the coarser of the fixed tolerance and a fraction of
// the chunk's distance from the cell: every chunk within its own bound, the
// distant ones coarser than the fixed one; with the fraction 0, none is. The
// room's chunks all touch the baked cell, so the cell is moved 10 m away.
TEST(Export, ChunkPositionsCoarsenWithDistanceFromTheCell) {
  const GeometryStore store(baked().store);
  Exported e = export_cell(baked().db("tdm"), false);
  e.cell.bounds = Box3d{e.cell.bounds.lo + Vec3d{10, 0, 0}, e.cell.bounds.hi + Vec3d{10, 0, 0}};
  GltfSceneContext context;
  context.lights = shading_lights(ShadingParams{}, context.up);
  for (const double per_distance : {0.0, 0.001}) {
    GltfExportOptions options;
    options.position_tolerance_per_distance = per_distance;
    e.bytes = export_cells_glb({{&e.row, &e.cell}}, store, context, options, &e.stats);
    const json doc = parse_glb(e.bytes).json;
    const int root = doc["scenes"][0]["nodes"][0];
    const std::vector<int> chunk_nodes = near_chunk_nodes(doc, doc["nodes"][root]["children"][0]);
    ASSERT_EQ(chunk_nodes.size(), e.cell.near_ids.size());
    std::size_t coarser = 0;
    for (std::size_t k = 0; k < chunk_nodes.size(); ++k) {
      const json& node = doc["nodes"][chunk_nodes[k]];
      const Vec3d t{node["translation"][0], node["translation"][1], node["translation"][2]};
      const double error = position_error_bound({t, node["scale"][0].get<double>()});
      const double distance = box_distance(e.cell.bounds, store.load(e.cell.near_ids[k])->bounds);
      EXPECT_LE(error, std::max(options.position_tolerance, per_distance * distance)) << node["name"];
      if (error > options.position_tolerance) ++coarser;
    }
    EXPECT_EQ(coarser > 0, per_distance > 0) << coarser << " of " << chunk_nodes.size() << " chunks coarser";
    // What drawing the cell reads from the store: its near chunks as stored.
    std::uint64_t stored = 0;
    for (std::int64_t id : e.cell.near_ids) stored += encode_chunk_blob(*store.load(id)).size();
    EXPECT_EQ(e.stats.store_chunk_bytes, stored);
    EXPECT_EQ(e.stats.store_chunks, e.cell.near_ids.size());
  }
}

TEST(Export, TexturedDepthMeshCarriesItsStoredImage) {
  const Exported e = export_cell(baked().db("tdm"), false);
  ASSERT_FALSE(e.cell.faces.empty());
  EXPECT_TRUE(e.cell.far_pieces.empty() && e.cell.far_whole_ids.empty());
  const ParsedGlb glb = parse_glb(e.bytes);
  const json& doc = glb.json;
  std::vector<int> faces;
  collect(doc, doc["scenes"][0]["nodes"][0], "face ", faces);
  ASSERT_EQ(faces.size(), e.cell.faces.size());
  EXPECT_EQ(e.stats.images, e.cell.faces.size());
  EXPECT_EQ(e.stats.images_reencoded, 0u);
  std::set<std::vector<std::uint8_t>> stored;
  for (const SampleRow& s : e.row.samples)
    for (const FaceRow& f : s.faces)
      if (f.image_format == "png") stored.insert(f.image);
  for (int node : faces) {
    const json& primitive = doc["meshes"][doc["nodes"][node]["mesh"].get<int>()]["primitives"][0];
    const json& material = doc["materials"][primitive["material"].get<int>()];
    EXPECT_TRUE(material["extensions"].contains("KHR_materials_unlit"));
    const json& texture = doc["textures"][material["pbrMetallicRoughness"]["baseColorTexture"]["index"].get<int>()];
    const json& sampler = doc["samplers"][texture["sampler"].get<int>()];
    EXPECT_EQ(sampler["wrapS"], 33071);  // clamped at the face's edges, as the viewer draws it
    const json& image = doc["images"][texture["source"].get<int>()];
    EXPECT_EQ(image["mimeType"], "image/png");
    const auto bytes = view_bytes(glb, image["bufferView"]);
    EXPECT_TRUE(stored.contains(std::vector<std::uint8_t>(bytes.begin(), bytes.end())));
    // Texture coordinates as uint16, within the face.
    const json& uv = doc["accessors"][primitive["attributes"]["TEXCOORD_0"].get<int>()];
    EXPECT_EQ(uv["componentType"], gltf::kUnsignedShort);
    EXPECT_FALSE(primitive["attributes"].contains("COLOR_0"));
  }
}

TEST(Export, CompressedStreamsDecodeToTheUncompressedOnes) {
  const Exported plain = export_cell(baked().db("tdm_avif"), false), packed = export_cell(baked().db("tdm_avif"), true);
  const ParsedGlb a = parse_glb(plain.bytes), b = parse_glb(packed.bytes);
  EXPECT_LT(packed.bytes.size(), plain.bytes.size());
  // AVIF faces: re-encoded as JPEG plainly, kept as stored when compressed.
  EXPECT_EQ(plain.stats.images_reencoded, plain.stats.images);
  EXPECT_EQ(packed.stats.images_reencoded, 0u);
  for (const json& image : a.json["images"]) EXPECT_EQ(image["mimeType"], "image/jpeg");
  for (const json& image : b.json["images"]) EXPECT_EQ(image["mimeType"], "image/avif");
  const json& required = b.json["extensionsRequired"];
  for (const char* ext : {"KHR_mesh_quantization", "EXT_meshopt_compression", "EXT_texture_avif"})
    EXPECT_NE(std::find(required.begin(), required.end(), ext), required.end()) << ext;
  EXPECT_TRUE(b.json["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"].get<bool>());
  ASSERT_EQ(a.json["bufferViews"].size(), b.json["bufferViews"].size());
  std::size_t compared = 0;
  for (std::size_t v = 0; v < b.json["bufferViews"].size(); ++v) {
    const json& view = b.json["bufferViews"][v];
    if (!view.contains("extensions")) continue;
    const json& ext = view["extensions"]["EXT_meshopt_compression"];
    const std::size_t count = ext["count"], stride = ext["byteStride"];
    const auto src = std::span<const std::uint8_t>(b.bin).subspan(ext["byteOffset"], ext["byteLength"]);
    std::vector<std::uint8_t> out(count * stride);
    const int rc = ext["mode"] == "ATTRIBUTES"
                       ? meshopt_decodeVertexBuffer(out.data(), count, stride, src.data(), src.size())
                       : meshopt_decodeIndexBuffer(out.data(), count, stride, src.data(), src.size());
    ASSERT_EQ(rc, 0) << "view " << v;
    const auto expected = view_bytes(a, int(v));
    if (ext["mode"] == "ATTRIBUTES") {
      EXPECT_EQ(out, std::vector<std::uint8_t>(expected.begin(), expected.end())) << "view " << v;
    } else {
      // The index codec keeps the triangles and their order but may rotate
      // each triangle's corners (same winding): compare with the smallest first.
      const auto triangles = [stride](std::span<const std::uint8_t> bytes) {
        std::vector<std::array<std::uint32_t, 3>> out;
        const auto at = [&](std::size_t i) {
          std::uint32_t x = 0;
          std::memcpy(&x, bytes.data() + i * stride, stride);
          return x;
        };
        for (std::size_t t = 0; t + 2 < bytes.size() / stride; t += 3) {
          std::array<std::uint32_t, 3> c{at(t), at(t + 1), at(t + 2)};
          std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
          out.push_back(c);
        }
        return out;
      };
      EXPECT_EQ(triangles(out), triangles(expected)) << "view " << v;
    }
    ++compared;
  }
  EXPECT_GE(compared, 4u);  // positions and uvs (each one view for the whole file) and indices
}

// The size of a compressed depth-mesh cell (AVIF faces, the bake's default)
// against what drawing it reads from the databases: its row's bytes plus the
// store chunks of its near field, each as the store codes it. Positions at
// the fewest bits within their tolerances and texture coordinates on the
// quarter-pixel grid make its binary chunk at least 10 % smaller than 16-bit
// positions and normalised uvs. Issue #38's 1.2x is measured on the demo (docs/benchmarks.md,
// E1); this 64-pixel room is small enough that the file's JSON is half of it
// (3.3x), so the bound here is that figure, which a larger file must not exceed.
TEST(Export, CompressedDepthMeshCellStaysSmall) {
  const Exported e = export_cell(baked().db("tdm_avif"), true);
  ASSERT_TRUE(e.cell.far_pieces.empty() && e.cell.far_whole_ids.empty());
  ASSERT_GT(e.stats.depth_mesh_triangles, 0u);
  const GeometryStore store(baked().store);
  std::uint64_t stored = e.row.bytes;
  for (std::int64_t id : e.cell.near_ids) stored += encode_chunk_blob(*store.load(id)).size();
  EXPECT_LE(double(e.bytes.size()) / double(stored), 3.4) << e.bytes.size() << " bytes against " << stored << " stored";

  GltfExportOptions full;
  full.compress = true;
  full.position_tolerance = 0;
  full.depth_mesh_tolerance = 0;
  full.uv_subpixels = 0;
  GltfSceneContext context;
  context.lights = shading_lights(ShadingParams{}, context.up);
  const std::vector<std::uint8_t> wide = export_cells_glb({{&e.row, &e.cell}}, store, context, full);
  const ParsedGlb narrow_glb = parse_glb(e.bytes), wide_glb = parse_glb(wide);
  // The binary chunk (streams and images; the JSON is nearly the same).
  EXPECT_LE(double(narrow_glb.bin.size()), 0.9 * double(wide_glb.bin.size()))
      << narrow_glb.bin.size() << " against " << wide_glb.bin.size();

  const json& doc = narrow_glb.json;
  const json& required = doc["extensionsRequired"];
  EXPECT_NE(std::find(required.begin(), required.end(), "KHR_texture_transform"), required.end());
  std::size_t transformed = 0;
  for (const json& material : doc["materials"]) {
    const json texture = material["pbrMetallicRoughness"].value("baseColorTexture", json::object());
    if (!texture.contains("extensions")) continue;
    const json& scale = texture["extensions"]["KHR_texture_transform"]["scale"];
    EXPECT_NEAR(scale[0].get<double>(), 1.0 / (64 * 4), 1e-12);  // 64-pixel faces, 4 steps a pixel
    ++transformed;
  }
  EXPECT_EQ(transformed, e.stats.images);  // every face
}

// A store chunk with a material texture: the texture embedded (rows top
// first, as image files hold them), texture coordinates flipped to glTF's
// top-left origin, the store's wrap modes. The cell is made by hand over the
// ingested checker quad (no bake needed: a near field of every chunk).
TEST(Export, TexturedChunkCarriesItsTextureWithGltfsUvOrigin) {
  test::TempDir dir;
  test::write_png_bottom_up(dir / "checker.png", test::checker_texels(8, 8), 64, 64);
  const auto obj = test::write_textured_quad_obj(dir.path(), "checker", test::checker_wall(), "checker", "checker.png");
  ingest_models({obj}, dir / "s.db", IngestParams{}, [](std::size_t n, const std::function<void(std::size_t)>& fn) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
  });
  const GeometryStore store(dir / "s.db");
  CellRow row;
  row.id = 1;
  row.status = "done";
  row.bounds = Box3d{{1, 5, 0.6}, {3, 7, 2.6}};
  DecodedCell cell;
  cell.id = 1;
  cell.bounds = row.bounds;
  for (const ChunkRef& r : store.query(store.model_bounds())) cell.near_ids.push_back(r.id);
  ASSERT_EQ(cell.near_ids.size(), 1u);
  GltfSceneContext context;
  context.lights = shading_lights(ShadingParams{}, context.up);
  const ParsedGlb glb = parse_glb(export_cells_glb({{&row, &cell}}, store, context, GltfExportOptions{}));
  const json& doc = glb.json;
  const json& primitive = doc["meshes"][0]["primitives"][0];
  const json& material = doc["materials"][primitive["material"].get<int>()];
  EXPECT_EQ(material["name"], "checker");
  const json& texture = doc["textures"][material["pbrMetallicRoughness"]["baseColorTexture"]["index"].get<int>()];
  EXPECT_EQ(doc["samplers"][texture["sampler"].get<int>()]["minFilter"], 9987);  // trilinear, as the viewer draws it
  const json& image = doc["images"][texture["source"].get<int>()];
  EXPECT_EQ(image["mimeType"], "image/jpeg");  // no alpha
  const auto bytes = view_bytes(glb, image["bufferView"]);
  const DecodedImage embedded = decode_image(std::vector<std::uint8_t>(bytes.begin(), bytes.end()));
  ASSERT_EQ(embedded.width, 64);
  // The image's top-left square is the checker's (u 0, v 1) square: i = 0, j = 7.
  const Rgba8 top_left = embedded.pixels[3 * 64 + 3], want = test::checker_square_colour(0, 7);
  EXPECT_NEAR(top_left.r, want.r, 12);
  EXPECT_NEAR(top_left.g, want.g, 12);
  EXPECT_NEAR(top_left.b, want.b, 12);
  // Corner c00 of the quad (world (4, 7, 0.6), the store's uv (0, 0)) has glTF uv (0, 1).
  const json& node = doc["nodes"][doc["scenes"][0]["nodes"][0].get<int>()];
  const json& info = node["extras"]["cellbake"];
  const int chunk_node = doc["nodes"][doc["nodes"][node["children"][0].get<int>()]["children"][0].get<int>()]["children"][0];
  const json& placed = doc["nodes"][chunk_node];
  const json& pos = doc["accessors"][primitive["attributes"]["POSITION"].get<int>()];
  const json& uv = doc["accessors"][primitive["attributes"]["TEXCOORD_0"].get<int>()];
  const auto p16 = accessor_bytes(glb, pos, 8), t16 = accessor_bytes(glb, uv, 4);
  bool found = false;
  for (std::size_t i = 0; i < pos["count"].get<std::size_t>(); ++i) {
    Vec3d world;
    for (int a = 0; a < 3; ++a) {
      std::int16_t q;
      std::memcpy(&q, p16.data() + 8 * i + 2 * a, 2);
      world[a] = info["origin"][a].get<double>() + placed["translation"][a].get<double>() +
                 placed["scale"][a].get<double>() * q / 32767.0;
    }
    if (length(world - Vec3d{4, 7, 0.6}) > 1e-3) continue;
    std::uint16_t u, v;
    std::memcpy(&u, t16.data() + 4 * i, 2);
    std::memcpy(&v, t16.data() + 4 * i + 2, 2);
    EXPECT_EQ(u, 0);
    EXPECT_EQ(v, 65535);
    found = true;
  }
  EXPECT_TRUE(found);
}

TEST(ExportCommand, WritesTheFileAndNamesAMissingCellOrStore) {
  test::TempDir dir;
  const auto out = dir / "cell.glb";
  const test::CommandResult ok =
      test::run_cellbake("export " + q(baked().db("tdm")) + " --cell 1 --store " + q(baked().store) + " --out " + q(out) + " --json");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  const json summary = json::parse(ok.output.substr(ok.output.find('{')));
  EXPECT_EQ(summary["bytes"], std::filesystem::file_size(out));
  EXPECT_EQ(parse_glb(read_bytes(out)).json["nodes"][1]["name"], "cell 1");
  const auto relit = dir / "relit.glb";
  ASSERT_EQ(test::run_cellbake("export " + q(baked().db("tdm")) + " --cell 1 --store " + q(baked().store) + " --out " + q(relit) +
                               " --normals --color-bits 16").exit_code, 0);
  const json doc = parse_glb(read_bytes(relit)).json;
  const json& chunk = doc["meshes"][0]["primitives"][0]["attributes"];  // the first near chunk's
  EXPECT_EQ(doc["accessors"][chunk["NORMAL"].get<int>()]["componentType"], gltf::kByte);
  EXPECT_EQ(doc["accessors"][chunk["COLOR_0"].get<int>()]["componentType"], gltf::kUnsignedShort);

  const test::CommandResult no_cell =
      test::run_cellbake("export " + q(baked().db("tdm")) + " --cell 7 --store " + q(baked().store) + " --out " + q(dir / "x.glb"));
  EXPECT_EQ(no_cell.exit_code, 1);
  EXPECT_NE(no_cell.output.find("cell 7 is not in"), std::string::npos) << no_cell.output;
  const test::CommandResult no_store =
      test::run_cellbake("export " + q(baked().db("tdm")) + " --cells 1- --store " + q(dir / "gone.db") + " --out " + q(dir / "x.glb"));
  EXPECT_EQ(no_store.exit_code, 1);
  EXPECT_NE(no_store.output.find("gone.db"), std::string::npos) << no_store.output;
  const test::CommandResult neither = test::run_cellbake("export " + q(baked().db("tdm")) + " --out " + q(dir / "x.glb"));
  EXPECT_NE(neither.exit_code, 0);
  EXPECT_NE(neither.output.find("--cell"), std::string::npos) << neither.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.glb"));
}

// ------------------------------------------- external tools (skip when absent)

// The folder holding node_modules with gltf-validator, three and playwright-core.
std::filesystem::path node_tools() {
  if (const char* env = std::getenv("CELLBAKE_NODE_TOOLS")) return env;
  return std::filesystem::path(CELLBAKE_SOURCE_DIR) / "node-tools";
}

bool have_node_package(const std::string& name) {
  return std::filesystem::exists(node_tools() / "node_modules" / name / "package.json");
}

std::string node_command(const std::string& script) {
  return "CELLBAKE_NODE_TOOLS=" + q(node_tools()) + " node " + q(std::filesystem::path(CELLBAKE_SOURCE_DIR) / "scripts" / script);
}

TEST(ExportTools, KhronosValidatorReportsNoErrors) {
  if (test::run_shell("node --version").exit_code != 0) GTEST_SKIP() << "no Node.js (apt-get install nodejs npm)";
  if (!have_node_package("gltf-validator"))
    GTEST_SKIP() << "no gltf-validator in " << node_tools() << " (scripts/install-node-tools.sh)";
  test::TempDir dir;
  for (const auto& [db, name] :
       {std::pair{baked().db("tdm"), "tdm"}, std::pair{baked().db("tdm_avif"), "tdm_avif"}, std::pair{baked().db("geometry"), "geometry"}}) {
    const auto out = dir / (std::string(name) + ".glb");
    const test::CommandResult ex = test::run_cellbake("export " + q(db) + " --cell 1 --store " + q(baked().store) + " --out " + q(out));
    ASSERT_EQ(ex.exit_code, 0) << ex.output;
    const test::CommandResult v = test::run_shell(node_command("validate-gltf.js") + " " + q(out));
    EXPECT_EQ(v.exit_code, 0) << v.output;
    const json report = json::parse(v.output.substr(v.output.find('{')));
    EXPECT_EQ(report["errors"], 0) << report.dump(1);
    std::printf("  %s: validator %s, %d errors, %d warnings, %d infos\n", name, report["validator"].get<std::string>().c_str(),
                report["errors"].get<int>(), report["warnings"].get<int>(), report["infos"].get<int>());
  }
}

double psnr_rgb(const DecodedImage& a, const DecodedImage& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) {
    const Rgba8 &p = a.pixels[i], &r = b.pixels[i];
    sum += double(p.r - r.r) * (p.r - r.r) + double(p.g - r.g) * (p.g - r.g) + double(p.b - r.b) * (p.b - r.b);
  }
  const double mse = sum / (3.0 * a.pixels.size());
  return mse > 0 ? 10 * std::log10(255.0 * 255.0 / mse) : 99;
}

TEST(ExportTools, ThreeJsRenderMatchesCellbakeRender) {
  if (test::run_shell("node --version").exit_code != 0) GTEST_SKIP() << "no Node.js (apt-get install nodejs npm)";
  if (!have_node_package("three") || !have_node_package("playwright-core"))
    GTEST_SKIP() << "no three / playwright-core in " << node_tools() << " (scripts/install-node-tools.sh)";
  const char* chromium = std::getenv("CHROMIUM");
  if (!std::filesystem::exists(chromium ? chromium : "/usr/bin/chromium"))
    GTEST_SKIP() << "no Chromium (apt-get install chromium, or CHROMIUM=path)";
  test::TempDir dir;
  const std::string view = " --eye 2,6,1.6 --look 12,6.5,1.4 --size 160x120";  // the cell's root sample point
  for (const auto& [db, compress] :
       {std::pair{baked().db("geometry"), false}, std::pair{baked().db("tdm_avif"), false}, std::pair{baked().db("tdm_avif"), true}}) {
    const auto glb = dir / "cell.glb", three = dir / "three.png", ours = dir / "ours.png";
    const test::CommandResult ex = test::run_cellbake("export " + q(db) + " --cell 1 --store " + q(baked().store) +
                                                      " --out " + q(glb) + (compress ? " --compress" : ""));
    ASSERT_EQ(ex.exit_code, 0) << ex.output;
    const test::CommandResult r = test::run_shell(node_command("three-render-glb.js") + " --glb " + q(glb) + view + " --out " + q(three));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const test::CommandResult c = test::run_cellbake("render " + q(db) + " --store " + q(baked().store) + view + " --out " + q(ours));
    ASSERT_EQ(c.exit_code, 0) << c.output;
    const DecodedImage a = decode_image(read_bytes(three)), b = decode_image(read_bytes(ours));
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    const double psnr = psnr_rgb(a, b);
    std::printf("  %s%s: three.js against cellbake render %.2f dB\n", db.filename().c_str(), compress ? " --compress" : "", psnr);
    EXPECT_GE(psnr, 30.0) << db << (compress ? " compressed" : "");
  }
}

}  // namespace
}  // namespace cellbake

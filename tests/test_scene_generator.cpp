// Tests for the procedural scene generator (stages/scene_*) and its streaming
// PLY writer (pipeline/scene_ply_writer).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "pipeline/scenes/scene_generator.h"
#include "pipeline/scenes/scene_math.h"
#include "pipeline/scenes/scene_ply_writer.h"
#include "pipeline/scenes/scene_primitives.h"
#include "pipeline/scenes/scene_random.h"
#include "test_support.h"

namespace cellbake {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Signed volume enclosed by the mesh (positive when wound outwards).
double signed_volume(const TriangleMesh& m) {
  double v = 0;
  for (std::size_t i = 0; i < m.indices.size(); i += 3)
    v += dot(m.positions[m.indices[i]], cross(m.positions[m.indices[i + 1]], m.positions[m.indices[i + 2]]));
  return v / 6;
}

// True when every directed edge is matched by exactly one opposite edge:
// the surface is closed and consistently oriented.
bool closed_and_consistent(const TriangleMesh& m) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  for (std::size_t i = 0; i < m.indices.size(); i += 3)
    for (int k = 0; k < 3; ++k) ++edges[{m.indices[i + k], m.indices[i + (k + 1) % 3]}];
  for (const auto& [e, n] : edges) {
    if (n != 1) return false;
    auto it = edges.find({e.second, e.first});
    if (it == edges.end() || it->second != 1) return false;
  }
  return true;
}

double triangle_area(Vec3d a, Vec3d b, Vec3d c) { return 0.5 * length(cross(b - a, c - a)); }

TEST(SceneMath, SinCosTurnsIsExactAtQuartersAndAccurateElsewhere) {
  EXPECT_EQ(sin_cos_turns(0).s, 0.0);
  EXPECT_EQ(sin_cos_turns(0).c, 1.0);
  EXPECT_EQ(sin_cos_turns(0.25).s, 1.0);
  EXPECT_EQ(sin_cos_turns(0.5).c, -1.0);
  EXPECT_EQ(sin_cos_turns(0.75).s, -1.0);
  for (int j = 0; j <= 997; ++j) {
    const double t = j / 997.0;
    EXPECT_NEAR(sin_cos_turns(t).s, std::sin(2 * kPi * t), 2e-15);
    EXPECT_NEAR(sin_cos_turns(t).c, std::cos(2 * kPi * t), 2e-15);
  }
}

TEST(SceneRandom, SequenceIsFixedAndUnitIsInRange) {
  SceneRng a(42), b(42), c(43);
  bool differs = false;
  for (int i = 0; i < 1000; ++i) {
    const std::uint64_t x = a.next();
    EXPECT_EQ(x, b.next());
    differs |= x != c.next();
    const double u = a.unit();
    b.unit();
    c.unit();
    EXPECT_GE(u, 0.0);
    EXPECT_LT(u, 1.0);
  }
  EXPECT_TRUE(differs);
  EXPECT_EQ(splitmix64(0), 0xE220A8397B1DCDAFull);  // published first output of splitmix64 seeded with 0
}

TEST(ScenePrimitives, BoxIsClosedOutwardWithExactVolume) {
  TriangleMesh m;
  append_box(m, {{1, 2, 3}, {3, 5, 7}}, {});
  ASSERT_EQ(m.triangle_count(), box_size().triangles);
  ASSERT_EQ(m.positions.size(), box_size().vertices);
  EXPECT_TRUE(closed_and_consistent(m));
  EXPECT_NEAR(signed_volume(m), 2.0 * 3.0 * 4.0, 1e-12);
  // A left-handed set of half axes is still wound outwards.
  TriangleMesh r;
  append_oriented_box(r, {0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 0.5}, {});
  EXPECT_NEAR(signed_volume(r), 2.0 * 2.0 * 1.0, 1e-12);
}

TEST(ScenePrimitives, LatheCylinderHasThePrismVolume) {
  const LatheSample profile[5] = {{0, 0}, {0.5, 0}, {0.5, 1}, {0.5, 2}, {0, 2}};
  const int n = 12;
  TriangleMesh m;
  append_lathe(m, {1, 1, 1}, {0, 0, 1}, profile, n, {});
  EXPECT_EQ(m.triangle_count(), lathe_size(profile, n).triangles);
  EXPECT_EQ(m.positions.size(), lathe_size(profile, n).vertices);
  EXPECT_TRUE(closed_and_consistent(m));
  const double polygon_area = 0.5 * n * 0.25 * std::sin(2 * kPi / n);
  EXPECT_NEAR(signed_volume(m), polygon_area * 2, 1e-12);
  const LatheSample bad[3] = {{0, 0}, {0, 1}, {1, 2}};
  EXPECT_THROW(lathe_size(bad, n), std::invalid_argument);
}

TEST(ScenePrimitives, BentCappedPipeIsClosedWithTubeVolume) {
  const Vec3d path[4] = {{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {2, 3, 1.5}};
  PipeStyle style;
  style.radius = 0.1;
  style.bend_radius = 0.4;
  style.segments = 64;
  style.bend_segments = 32;
  style.max_piece_length = 0.25;
  TriangleMesh m;
  append_pipe(m, path, style, {});
  EXPECT_EQ(m.triangle_count(), pipe_size(path, style).triangles);
  EXPECT_EQ(m.positions.size(), pipe_size(path, style).vertices);
  EXPECT_TRUE(closed_and_consistent(m));
  // Pappus: a tube's volume is its cross-section times its centre-line length;
  // each 90-degree bend shortens the path by (2 - pi/2) r_b.
  const double centre_line = 2 + 3 + 1.5 - 2 * (2 - kPi / 2) * 0.4;
  EXPECT_NEAR(signed_volume(m), kPi * 0.01 * centre_line, 0.01 * kPi * 0.01 * centre_line);
  for (std::size_t i = 0; i < m.indices.size(); i += 3)
    ASSERT_GT(triangle_area(m.positions[m.indices[i]], m.positions[m.indices[i + 1]],
                            m.positions[m.indices[i + 2]]),
              1e-8);
}

TEST(ScenePrimitives, PipeRejectsPathsItCannotSweep) {
  PipeStyle style;
  const Vec3d slanted[3] = {{0, 0, 0}, {1, 0, 0}, {2, 1, 0}};
  EXPECT_THROW(pipe_size(slanted, style), std::invalid_argument);
  const Vec3d repeated[3] = {{0, 0, 0}, {0, 0, 0}, {1, 0, 0}};
  EXPECT_THROW(pipe_size(repeated, style), std::invalid_argument);
  const Vec3d cramped[3] = {
      {0, 0, 0}, {0.05, 0, 0}, {0.05, 1, 0}};  // leg too short for a bend of a 5 cm pipe
  EXPECT_THROW(pipe_size(cramped, style), std::invalid_argument);
}

TEST(SceneGenerator, ParsesKindsAndRejectsOthers) {
  EXPECT_EQ(parse_scene_kind("plant"), SceneKind::plant);
  EXPECT_EQ(parse_scene_kind("house"), SceneKind::house);
  EXPECT_EQ(parse_scene_kind("city"), SceneKind::city);
  EXPECT_THROW(parse_scene_kind("ship"), std::invalid_argument);
}

struct SceneStats {
  SceneSummary summary;
  std::uint64_t triangles = 0, vertices = 0, parts = 0, max_part = 0;
  Box3d bounds;
  double min_area = 1e300;
  bool indices_in_range = true, colours_per_vertex = true;
};

SceneStats generate_and_check(SceneKind kind, std::uint64_t target, bool check_areas) {
  SceneStats s;
  SceneParams params;
  params.kind = kind;
  params.target_triangles = target;
  s.summary = generate_scene(params, [&](const TriangleMesh& part) {
    ++s.parts;
    s.triangles += part.triangle_count();
    s.vertices += part.positions.size();
    s.max_part = std::max<std::uint64_t>(s.max_part, part.triangle_count());
    s.colours_per_vertex &= part.colors.size() == part.positions.size();
    for (std::uint32_t i : part.indices) s.indices_in_range &= i < part.positions.size();
    for (const Vec3d& p : part.positions) s.bounds.expand(p);
    if (!check_areas) return;
    auto f = [](Vec3d p) {  // as written to PLY
      return Vec3d{static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
    };
    for (std::size_t i = 0; i < part.indices.size(); i += 3) {
      const Vec3d a = part.positions[part.indices[i]], b = part.positions[part.indices[i + 1]],
                  c = part.positions[part.indices[i + 2]];
      s.min_area = std::min({s.min_area, triangle_area(a, b, c), triangle_area(f(a), f(b), f(c))});
    }
  });
  return s;
}

class SceneKinds : public ::testing::TestWithParam<SceneKind> {};

TEST_P(SceneKinds, HundredThousandIsOnTargetWellFormedAndNonDegenerate) {
  const SceneStats s = generate_and_check(GetParam(), 100'000, true);
  EXPECT_NEAR(static_cast<double>(s.triangles), 100'000.0, 10'000.0);
  EXPECT_EQ(s.summary.triangles, s.triangles);
  EXPECT_EQ(s.summary.vertices, s.vertices);
  EXPECT_EQ(s.summary.bounds, s.bounds);
  EXPECT_TRUE(s.indices_in_range);
  EXPECT_TRUE(s.colours_per_vertex);
  EXPECT_GT(s.min_area, 1e-7) << "a triangle is (nearly) degenerate";  // m^2, in double and in float32
  // Bounds: metres, near the origin, z up from just below the ground.
  EXPECT_GE(s.bounds.lo.z, -1.0);
  EXPECT_LE(s.bounds.hi.z, 200.0);
  EXPECT_GT(s.bounds.extent().x, 10.0);
  EXPECT_LT(s.bounds.extent().x, 2000.0);
  EXPECT_GT(s.bounds.extent().z, 5.0);
}

TEST_P(SceneKinds, MillionIsOnTargetInBoundedParts) {
  const SceneStats s = generate_and_check(GetParam(), 1'000'000, false);
  EXPECT_NEAR(static_cast<double>(s.triangles), 1'000'000.0, 100'000.0);
  EXPECT_TRUE(s.indices_in_range);
  EXPECT_GE(s.parts, 5u);
  EXPECT_LE(s.max_part, 400'000u);
}

INSTANTIATE_TEST_SUITE_P(All, SceneKinds,
                         ::testing::Values(SceneKind::plant, SceneKind::house, SceneKind::city),
                         [](const auto& info) {
                           return std::string(info.param == SceneKind::plant   ? "plant"
                                              : info.param == SceneKind::house ? "house"
                                                                               : "city");
                         });

TEST(SceneGenerator, PlantHasTheHallsFixedSizeAtAnyDensity) {
  for (std::uint64_t target : {100'000ull, 1'000'000ull}) {
    const SceneStats s = generate_and_check(SceneKind::plant, target, false);
    EXPECT_NEAR(s.bounds.lo.x, -0.5, 1e-9);
    EXPECT_NEAR(s.bounds.hi.x, 60.5, 1e-9);
    EXPECT_NEAR(s.bounds.hi.y, 40.5, 1e-9);
    EXPECT_NEAR(s.bounds.hi.z, 30.4, 1e-9);
  }
}

std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

SceneParams params_for(SceneKind kind, std::uint64_t seed) {
  SceneParams p;
  p.kind = kind;
  p.target_triangles = 100'000;
  p.seed = seed;
  return p;
}

TEST(ScenePlyWriter, SameSeedGivesIdenticalBytesAndAnotherSeedDoesNot) {
  test::TempDir dir;
  for (SceneKind kind : {SceneKind::plant, SceneKind::house, SceneKind::city}) {
    generate_scene_to_ply(params_for(kind, 5), dir / "a.ply");
    generate_scene_to_ply(params_for(kind, 5), dir / "b.ply");
    generate_scene_to_ply(params_for(kind, 6), dir / "c.ply");
    const std::string a = read_bytes(dir / "a.ply");
    EXPECT_GT(a.size(), 1'000'000u);
    EXPECT_EQ(a, read_bytes(dir / "b.ply"));
    EXPECT_NE(a, read_bytes(dir / "c.ply"));
  }
}

TEST(ScenePlyWriter, HeaderCountsRecordSizesAndFileSizeAgree) {
  test::TempDir dir;
  const auto out = dir / "plant.ply";
  const SceneSummary summary = generate_scene_to_ply(params_for(SceneKind::plant, 1), out);
  const std::string bytes = read_bytes(out);
  const std::size_t header_end = bytes.find("end_header\n");
  ASSERT_NE(header_end, std::string::npos);
  const std::size_t header_size = header_end + std::strlen("end_header\n");
  std::istringstream header(bytes.substr(0, header_size));
  std::string line;
  std::uint64_t vertices = 0, faces = 0;
  std::vector<std::string> properties;
  std::getline(header, line);
  EXPECT_EQ(line, "ply");
  std::getline(header, line);
  EXPECT_EQ(line, "format binary_little_endian 1.0");
  while (std::getline(header, line)) {
    std::istringstream words(line);
    std::string word, name;
    words >> word;
    if (word == "element") {
      std::uint64_t n = 0;
      words >> name >> n;
      (name == "vertex" ? vertices : faces) = n;
    } else if (word == "property") {
      properties.push_back(line);
    }
  }
  EXPECT_EQ(vertices, summary.vertices);
  EXPECT_EQ(faces, summary.triangles);
  ASSERT_EQ(properties.size(), 8u);
  EXPECT_EQ(properties[0], "property float x");
  EXPECT_EQ(properties[6], "property uchar alpha");
  EXPECT_EQ(properties[7], "property list uchar uint vertex_indices");
  constexpr std::uint64_t kVertexRecord = 3 * 4 + 4, kFaceRecord = 1 + 3 * 4;
  ASSERT_EQ(header_size + vertices * kVertexRecord + faces * kFaceRecord, bytes.size());
  // Every face is a triangle with in-range indices; positions lie in the summary bounds.
  const char* face_data = bytes.data() + header_size + vertices * kVertexRecord;
  for (std::uint64_t f = 0; f < faces; ++f) {
    const char* rec = face_data + f * kFaceRecord;
    ASSERT_EQ(rec[0], 3);
    for (int k = 0; k < 3; ++k) {
      std::uint32_t index;
      std::memcpy(&index, rec + 1 + 4 * k, 4);
      ASSERT_LT(index, vertices);
    }
  }
  for (std::uint64_t v = 0; v < vertices; v += 997) {
    float p[3];
    std::memcpy(p, bytes.data() + header_size + v * kVertexRecord, sizeof p);
    EXPECT_GE(p[0], summary.bounds.lo.x - 1e-3);
    EXPECT_LE(p[2], summary.bounds.hi.z + 1e-3);
  }
  // Only the output is left behind.
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1u);
}

TEST(ScenePlyWriter, UnwritableOutputThrowsNamingTheFileAndLeavesNothing) {
  test::TempDir dir;
  const auto out = dir / "missing-folder" / "scene.ply";
  try {
    generate_scene_to_ply(params_for(SceneKind::house, 1), out);
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing-folder"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace cellbake

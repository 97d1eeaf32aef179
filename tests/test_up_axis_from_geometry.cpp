// stages/up_axis_from_geometry: plane scores with analytic answers, a house
// found Z-up as built and Y-up turned, the unsure answers (a cube, curved
// geometry, an X-up house), terrain found by the area facing up (issue #38
// item 5), a ChunkSource read equal to the accumulator, and ingest using it:
// recorded when the file says nothing, a warning when --up contradicts flat
// planes.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "pipeline/ingest.h"
#include "runner/parallel.h"
#include "stages/model_analysis/up_axis_from_geometry.h"
#include "tests/fixture_house_model.h"
#include "tests/fixture_memory_chunk_source.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using Tris = std::vector<test::HouseTriangle>;

Box3d bounds_of(const Tris& tris) {
  Box3d b;
  for (const auto& t : tris)
    for (const Vec3d& p : t) b.expand(p);
  return b;
}

UpAxisGuess guess_of(const Tris& tris, const UpAxisParams& params = {}) {
  UpAxisEvidence evidence(bounds_of(tris), params);
  for (const auto& t : tris) evidence.add_triangle(t[0], t[1], t[2]);
  return evidence.guess();
}

// Each corner mapped by `f`.
template <class F>
Tris turned(const Tris& tris, F f) {
  Tris out = tris;
  for (auto& t : out)
    for (Vec3d& p : t) p = f(p);
  return out;
}

// A horizontal square of side `s` at height z (two triangles).
void square(Tris& t, double z, double s) {
  t.push_back({Vec3d{0, 0, z}, Vec3d{s, 0, z}, Vec3d{s, s, z}});
  t.push_back({Vec3d{0, 0, z}, Vec3d{s, s, z}, Vec3d{0, s, z}});
}

TEST(UpAxisFromGeometry, PlaneScoresAreTheChanceThatTwoSurfacePointsShareAPlane) {
  Tris one;
  square(one, 0, 10);
  const UpAxisGuess g = guess_of(one);
  EXPECT_DOUBLE_EQ(g.score[2], 1.0);  // all the area on one plane facing z
  EXPECT_EQ(g.score[0], 0.0);
  EXPECT_EQ(g.score[1], 0.0);
  EXPECT_EQ(g.axis, "z");

  // Two equal squares far apart: each pair of points lies on one plane half the time.
  Tris two;
  square(two, 0, 10);
  square(two, 5, 10);
  EXPECT_NEAR(guess_of(two).score[2], 0.5, 1e-12);
  // A third square of the same size standing vertically (facing x): z 2 x (1/3)^2, x (1/3)^2.
  two.push_back({Vec3d{0, 0, 0}, Vec3d{0, 10, 0}, Vec3d{0, 10, 10}});
  two.push_back({Vec3d{0, 0, 0}, Vec3d{0, 10, 10}, Vec3d{0, 0, 10}});
  const UpAxisGuess three = guess_of(two);
  EXPECT_NEAR(three.score[2], 2.0 / 9, 1e-12);
  EXPECT_NEAR(three.score[0], 1.0 / 9, 1e-12);
  EXPECT_NEAR(three.ratio, 2.0, 1e-9);
}

TEST(UpAxisFromGeometry, AHouseIsZUpAsBuiltAndYUpTurned) {
  const Tris house = test::house_triangles();
  const UpAxisGuess z = guess_of(house);
  EXPECT_EQ(z.axis, "z") << z.evidence;
  EXPECT_GT(z.ratio, 3.0) << z.evidence;
  EXPECT_NE(z.evidence.find("large flat surfaces face z"), std::string::npos) << z.evidence;
  const UpAxisGuess y = guess_of(turned(house, [](Vec3d p) { return Vec3d{p.x, p.z, -p.y}; }));
  EXPECT_EQ(y.axis, "y") << y.evidence;
  // Turned the other way round (Y-down is still "y": the axis, not its sign).
  EXPECT_EQ(guess_of(turned(house, [](Vec3d p) { return Vec3d{p.x, -p.z, p.y}; })).axis, "y");
  // Deterministic: the same triangles in the same order give the same bits.
  const UpAxisGuess again = guess_of(house);
  EXPECT_EQ(again.score, z.score);
  EXPECT_EQ(again.evidence, z.evidence);
}

TEST(UpAxisFromGeometry, IsUnsureWhenNoAxisStandsOutOrFlatSurfacesAreFew) {
  Tris cube;
  test::add_box(cube, {0, 0, 0}, {4, 4, 4}, 3);
  const UpAxisGuess c = guess_of(cube);
  EXPECT_EQ(c.axis, "");
  EXPECT_NE(c.evidence.find("no axis stands out"), std::string::npos) << c.evidence;

  // A tessellated sphere: no facet lies within 10 degrees of an axis except near the poles' few.
  Tris sphere;
  const int n = 24;
  const auto at = [&](int i, int j) {
    const double th = M_PI * (i + 0.5) / n, ph = 2 * M_PI * j / n;
    return Vec3d{std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
  };
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j < n; ++j) {
      sphere.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      sphere.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  const UpAxisGuess s = guess_of(sphere);
  EXPECT_EQ(s.axis, "");
  EXPECT_NE(s.evidence.find("too few large flat surfaces"), std::string::npos) << s.evidence;

  // A house lying with its floors facing x: not an axis cellbake bakes.
  const UpAxisGuess x = guess_of(turned(test::house_triangles(), [](Vec3d p) {
    return Vec3d{p.z, p.y, -p.x};
  }));
  EXPECT_EQ(x.axis, "");
  EXPECT_NE(x.evidence.find("face x"), std::string::npos) << x.evidence;

  EXPECT_EQ(guess_of({}).axis, "");
}

// Rolling terrain (issue #38 item 5): a Y-up height field y = f(x) + g(z) of
// triangle waves with slopes of 0.4, so every facet lies 29.5 degrees off up
// (none within the planes' 10 degrees), with 20 "trees" (open square prisms
// whose walls face x and z exactly): 200 area units of ground, 80 of walls.
Tris terrain_with_trees() {
  Tris t;
  const auto wave = [](double u) { return 0.4 * std::abs(std::fmod(u, 4.0) - 2.0); };  // slope +-0.4
  const auto at = [&](double x, double z) { return Vec3d{x, wave(x) + wave(z + 1), z}; };
  const double step = 1.0;  // the waves' kinks fall on grid lines: each facet is planar
  for (double x = 0; x < 20; x += step)
    for (double z = 0; z < 10; z += step) {
      t.push_back({at(x, z), at(x, z + step), at(x + step, z + step)});
      t.push_back({at(x, z), at(x + step, z + step), at(x + step, z)});
    }
  for (int k = 0; k < 20; ++k) {  // a 1 x 1 prism 1 high at (x0, z0): four walls of area 1
    // Every wall at a coordinate of its own: no two make one plane.
    const double x0 = 0.5 + (k % 10) * 1.9 + 0.07 * (k / 10), z0 = 1.5 + (k / 10) * 5.3 + 0.13 * (k % 10);
    const double y0 = 1.0 + 0.37 * k, y1 = y0 + 1;
    const Vec3d c[4] = {{x0, 0, z0}, {x0 + 1, 0, z0}, {x0 + 1, 0, z0 + 1}, {x0, 0, z0 + 1}};
    for (int e = 0; e < 4; ++e) {
      const Vec3d a = c[e], b = c[(e + 1) % 4];
      t.push_back({Vec3d{a.x, y0, a.z}, Vec3d{b.x, y0, b.z}, Vec3d{b.x, y1, b.z}});
      t.push_back({Vec3d{a.x, y0, a.z}, Vec3d{b.x, y1, b.z}, Vec3d{a.x, y1, a.z}});
    }
  }
  return t;
}

TEST(UpAxisFromGeometry, TerrainIsFoundByTheAreaFacingUpWhenNothingIsFlat) {
  const Tris terrain = terrain_with_trees();
  const UpAxisGuess y = guess_of(terrain);
  EXPECT_EQ(y.score[1], 0.0);  // no facet within 10 degrees of up
  EXPECT_LT(std::max(y.score[0], y.score[2]), UpAxisParams{}.min_score);  // the walls are no large planes
  const double ground = 200 * std::sqrt(1 + 2 * 0.4 * 0.4), walls = 80;  // slanted facets' area, walls'
  EXPECT_NEAR(y.facing[1], ground / (ground + walls), 1e-9);
  EXPECT_NEAR(y.facing[0], 40 / (ground + walls), 1e-9);
  EXPECT_NEAR(y.facing[2], 40 / (ground + walls), 1e-9);
  EXPECT_EQ(y.axis, "y");
  EXPECT_TRUE(y.from_facing);
  EXPECT_NE(y.evidence.find("as terrain does"), std::string::npos) << y.evidence;
  // Turned Z-up: z.
  const UpAxisGuess z = guess_of(turned(terrain, [](Vec3d p) { return Vec3d{p.x, -p.z, p.y}; }));
  EXPECT_EQ(z.axis, "z");
  EXPECT_NEAR(z.facing[2], y.facing[1], 1e-9);
  // Four times the walls: the ground is 42 % of the area, under the majority needed: unsure.
  Tris forest = terrain;
  for (int copy = 0; copy < 3; ++copy) {
    const Tris more = terrain_with_trees();
    forest.insert(forest.end(), more.end() - 160, more.end());  // the 20 trees' 160 wall triangles
  }
  const UpAxisGuess dense = guess_of(forest);  // ground 230, walls 320
  EXPECT_EQ(dense.axis, "");
  EXPECT_FALSE(dense.from_facing);
  // A cube (1/3 of the area each) stays unsure.
  Tris cube;
  test::add_box(cube, {0, 0, 0}, {4, 4, 4}, 3);
  const UpAxisGuess c = guess_of(cube);
  EXPECT_NEAR(c.facing[0], 1.0 / 3, 1e-9);
  EXPECT_EQ(c.axis, "");
}

TEST(UpAxisFromGeometry, AChunkSourceGivesWhatTheAccumulatorGives) {
  const Tris house = test::house_triangles();
  test::MemoryChunkSource source;
  const std::size_t half = house.size() / 2;
  source.add(test::make_memory_chunk(1, Tris(house.begin(), house.begin() + half)));
  source.add(test::make_memory_chunk(2, Tris(house.begin() + half, house.end()), {7, 5, 3}));
  const UpAxisGuess from_source = up_axis_from_geometry(source);
  EXPECT_EQ(from_source.axis, "z");
  const UpAxisGuess direct = guess_of(house);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(from_source.score[a], direct.score[a], 1e-6);
}

TEST(UpAxisFromGeometry, IngestRecordsItWhenTheFileSaysNothingAndWarnsWhenUpDisagrees) {
  test::TempDir dir;
  const auto obj = dir / "house.obj";
  std::ofstream(obj, std::ios::binary) << test::triangles_obj(turned(test::house_triangles(), [](Vec3d p) {
    return Vec3d{p.x, p.z, -p.y};
  }));
  const IngestReport detected = ingest_models({obj}, dir / "a.store.db", {}, tbb_parallel_for());
  EXPECT_EQ(detected.up, "y");
  EXPECT_EQ(detected.up_source.rfind("detected from the geometry: large flat surfaces face y", 0), 0u)
      << detected.up_source;
  EXPECT_EQ(detected.up_warning, "");

  IngestParams given;
  given.up = "z";
  const IngestReport contradicted = ingest_models({obj}, dir / "b.store.db", given, tbb_parallel_for());
  EXPECT_EQ(contradicted.up, "z");  // --up wins
  EXPECT_EQ(contradicted.up_source, "--up");
  EXPECT_NE(contradicted.up_warning.find("recorded is z (--up) but the geometry looks y-up"),
            std::string::npos)
      << contradicted.up_warning;

  given.up = "y";
  const IngestReport agreed = ingest_models({obj}, dir / "c.store.db", given, tbb_parallel_for());
  EXPECT_EQ(agreed.up_source, "--up; the geometry agrees");
  EXPECT_EQ(agreed.up_warning, "");
}

// Terrain in an OBJ (which records no axis): ingest records y from the area
// facing it; --up z is kept without a warning (only flat planes contradict).
TEST(UpAxisFromGeometry, IngestRecordsTerrainsAxisAndNeverWarnsFromIt) {
  test::TempDir dir;
  const auto obj = dir / "terrain.obj";
  std::ofstream(obj, std::ios::binary) << test::triangles_obj(terrain_with_trees());
  const IngestReport detected = ingest_models({obj}, dir / "a.store.db", {}, tbb_parallel_for());
  EXPECT_EQ(detected.up, "y");
  EXPECT_NE(detected.up_source.find("as terrain does"), std::string::npos) << detected.up_source;
  IngestParams given;
  given.up = "z";
  const IngestReport kept = ingest_models({obj}, dir / "b.store.db", given, tbb_parallel_for());
  EXPECT_EQ(kept.up, "z");
  EXPECT_EQ(kept.up_warning, "");
}

}  // namespace
}  // namespace cellbake

// stages/up_axis_from_geometry: plane scores with analytic answers, a house
// found Z-up as built and Y-up turned, the unsure answers (a cube, curved
// geometry, an X-up house), a ChunkSource read equal to the accumulator, and
// ingest using it: recorded when the file says nothing, a warning when --up
// contradicts it.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "pipeline/ingest.h"
#include "runner/parallel.h"
#include "stages/up_axis_from_geometry.h"
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

}  // namespace
}  // namespace cellbake

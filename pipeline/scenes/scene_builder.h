// Collects the primitives of a procedural scene. In counting mode it only adds
// up exact triangle counts (cheap, used to choose the density before emitting);
// in emitting mode it appends them to a part mesh and hands each part to a
// callback once it holds about `part_triangles` triangles, so memory stays
// bounded by one part. Both modes see the same calls, so the count is exact.
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "pipeline/scenes/scene_generator.h"
#include "pipeline/scenes/scene_primitives.h"
#include "stages/geometry.h"

namespace cellbake {

// The density of a scene as two numbers >= 1: `structure` sets how many
// objects there are (rooms, blocks, tube banks), `tessellation` how finely each
// is cut (segments around, piece lengths, bar and mullion pitch). The generator
// first raises both together, then only tessellation to fine-tune the count.
struct SceneDensity {
  double structure = 1;
  double tessellation = 1;
};

class SceneBuilder {
 public:
  using Emit = std::function<void(const TriangleMesh&)>;

  // Counting mode: nothing is built, triangles() is the exact total.
  SceneBuilder() = default;
  // Emitting mode: parts go to `emit` (which must outlive the builder). A part
  // exceeds `part_triangles` only when a single primitive is larger.
  SceneBuilder(const Emit& emit, std::uint64_t part_triangles);

  void box(const Box3d& box, Rgba8 color);
  void oriented_box(Vec3d center, Vec3d half_u, Vec3d half_v, Vec3d half_w, Rgba8 color);
  void lathe(Vec3d base, Vec3d axis, std::span<const LatheSample> profile, int segments, Rgba8 color);
  void pipe(std::span<const Vec3d> path, const PipeStyle& style, Rgba8 color);

  std::uint64_t triangles() const { return triangles_; }

  // Emits the last part and returns the totals (bounds stay empty in counting mode).
  SceneSummary finish();

 private:
  // Makes room for a primitive of `size` (flushing the part if needed) and
  // records the count; returns false in counting mode.
  bool reserve(PrimitiveSize size);
  void check_appended(PrimitiveSize size, std::size_t triangles_before, std::size_t vertices_before) const;
  void flush();

  const Emit* emit_ = nullptr;
  std::uint64_t part_triangles_ = 0;
  TriangleMesh part_;
  std::uint64_t triangles_ = 0;
  std::uint64_t vertices_ = 0;
  Box3d bounds_;
};

// Chooses tessellation for the scene's round and long parts from a chord
// tolerance and a maximum straight piece length. Each call draws a per-object
// factor in [0.7, 1.3) from a hash of (seed, call number) so that objects of
// equal size do not all change segment count at the same density, which keeps
// the scene's triangle count a fine-grained function of the density.
class SceneTessellation {
 public:
  SceneTessellation(double chord_tolerance, double max_piece_length, std::uint64_t seed)
      : tolerance_(chord_tolerance), piece_(max_piece_length), seed_(seed) {}

  // Segments around a circle of radius `radius` (metres), within [min_segments, 256].
  int circle_segments(double radius, int min_segments = 6);
  // Segments along a 90-degree bend of centre-line radius `bend_radius`, >= 1.
  int bend_segments(double bend_radius);
  // Straight piece length for a pipe (>= 0.02 m).
  double piece_length();

 private:
  double stagger();
  double tolerance_;
  double piece_;
  std::uint64_t seed_;
  std::uint64_t calls_ = 0;
};

}  // namespace cellbake

#include "pipeline/scenes/scene_builder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "pipeline/scenes/scene_random.h"

namespace cellbake {

SceneBuilder::SceneBuilder(const Emit& emit, std::uint64_t part_triangles)
    : emit_(&emit), part_triangles_(std::max<std::uint64_t>(part_triangles, 1)) {}

bool SceneBuilder::reserve(PrimitiveSize size) {
  triangles_ += size.triangles;
  vertices_ += size.vertices;
  if (!emit_) return false;
  if (!part_.indices.empty() && part_.triangle_count() + size.triangles > part_triangles_) flush();
  if (part_.positions.size() + size.vertices > 0xFFFFFFFFull)
    throw std::length_error("scene builder: one primitive has more than 2^32 vertices");
  return true;
}

void SceneBuilder::check_appended(PrimitiveSize size, std::size_t triangles_before,
                                  std::size_t vertices_before) const {
  if (part_.triangle_count() - triangles_before != size.triangles ||
      part_.positions.size() - vertices_before != size.vertices)
    throw std::logic_error("scene builder: a primitive emitted " +
                           std::to_string(part_.triangle_count() - triangles_before) +
                           " triangles but its planned count was " + std::to_string(size.triangles));
}

void SceneBuilder::box(const Box3d& box, Rgba8 color) {
  if (!reserve(box_size())) return;
  const std::size_t t = part_.triangle_count(), v = part_.positions.size();
  append_box(part_, box, color);
  check_appended(box_size(), t, v);
}

void SceneBuilder::oriented_box(Vec3d center, Vec3d half_u, Vec3d half_v, Vec3d half_w, Rgba8 color) {
  if (!reserve(box_size())) return;
  const std::size_t t = part_.triangle_count(), v = part_.positions.size();
  append_oriented_box(part_, center, half_u, half_v, half_w, color);
  check_appended(box_size(), t, v);
}

void SceneBuilder::lathe(Vec3d base, Vec3d axis, std::span<const LatheSample> profile, int segments,
                         Rgba8 color) {
  const PrimitiveSize size = lathe_size(profile, segments);
  if (!reserve(size)) return;
  const std::size_t t = part_.triangle_count(), v = part_.positions.size();
  append_lathe(part_, base, axis, profile, segments, color);
  check_appended(size, t, v);
}

void SceneBuilder::pipe(std::span<const Vec3d> path, const PipeStyle& style, Rgba8 color) {
  const PrimitiveSize size = pipe_size(path, style);
  if (!reserve(size)) return;
  const std::size_t t = part_.triangle_count(), v = part_.positions.size();
  append_pipe(part_, path, style, color);
  check_appended(size, t, v);
}

void SceneBuilder::flush() {
  if (part_.indices.empty()) return;
  for (const Vec3d& p : part_.positions) bounds_.expand(p);
  (*emit_)(part_);
  part_.positions.clear();
  part_.colors.clear();
  part_.indices.clear();
}

SceneSummary SceneBuilder::finish() {
  if (emit_) flush();
  SceneSummary summary;
  summary.triangles = triangles_;
  summary.vertices = vertices_;
  summary.bounds = bounds_;
  return summary;
}

double SceneTessellation::stagger() {
  return 0.7 + 0.6 * unit_from_bits(splitmix64(seed_ ^ splitmix64(++calls_)));
}

int SceneTessellation::circle_segments(double radius, int min_segments) {
  // A chord of a circle cut into n segments strays r (1 - cos(pi/n)) ~ r pi^2 / (2 n^2) from it.
  const double tolerance = tolerance_ * stagger();
  const double n = std::ceil(3.14159265358979 * std::sqrt(radius / (2.0 * tolerance)));
  return static_cast<int>(std::clamp(n, static_cast<double>(min_segments), 256.0));
}

int SceneTessellation::bend_segments(double bend_radius) {
  const double n = std::ceil(static_cast<double>(circle_segments(bend_radius, 4)) / 4.0);
  return std::max(1, static_cast<int>(n));
}

double SceneTessellation::piece_length() { return std::max(0.02, piece_ * stagger()); }

}  // namespace cellbake

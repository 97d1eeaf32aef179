// Frame-time control for the interactive viewer (issue #38: frames that stay
// under a target on a software rasteriser): the triangles a frame may draw,
// from the milliseconds per triangle of recent frames. Frame time grows with
// the triangles drawn (a fixed cost plus a cost per triangle); budgeting
// target / (median recent ms per triangle) converges on frames of the target
// length where the scene allows, since the ratio falls as frames shrink.
// Pure: no clock, no GL.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>

namespace cellbake {

class FrameTimeBudget {
 public:
  // target_ms > 0: the frame time aimed at; `window` frames are remembered.
  explicit FrameTimeBudget(double target_ms, std::size_t window = 16);

  // A frame took `frame_ms` drawing `triangles` (frames drawing none are ignored).
  void add(double frame_ms, std::uint64_t triangles);

  // The triangles the next frame may draw; 0 (no limit) until a frame was added.
  std::uint64_t triangles() const;

  double target_ms() const { return target_ms_; }

 private:
  double target_ms_;
  std::size_t window_;
  std::deque<double> ms_per_triangle_;
};

// What a frame's chunks (near field, exact far geometry) may draw:
// `frame_triangles` less what it draws otherwise (depth meshes), at least 1
// (then the chunks are drawn as coarse as their levels go); 0 (no limit)
// when frame_triangles is 0.
std::uint64_t chunk_allowance(std::uint64_t frame_triangles, std::uint64_t other_triangles);

}  // namespace cellbake

// Cameras for the viewers: a look-at pinhole camera with a vertical field of
// view, and frustum culling of a chunked model against it (for ground truth).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "stages/chunk_source.h"
#include "stages/render/chunk_renderer.h"

namespace cellbake {

// The model's up axis from the cell database's meta `up` ("z" or "y").
// Throws std::invalid_argument for anything else.
Vec3d up_axis(const std::string& up);

// A camera at `eye` looking at `look`, with `world_up` kept upright, a vertical
// field of view `fov_y_deg` (0 < fov < 180) and the aspect of width x height.
// When the view direction is parallel to world_up another upright axis is
// chosen. Throws std::invalid_argument when eye == look, the fov or the size is
// out of range or anything is not finite.
RenderCamera look_at_camera(const Vec3d& eye, const Vec3d& look, const Vec3d& world_up, double fov_y_deg, int width,
                            int height, double near_plane = 0.01);

// Whether any part of world box `box` can be inside the camera's frustum
// (conservative: false only when the box lies wholly behind the near plane or
// outside one side plane). An empty box is never in view.
bool box_in_view(const RenderCamera& camera, const Box3d& box);

// Ids of every chunk of `source` whose bounds meet the camera's frustum (its
// four side planes and near plane, out to the model's bounds), sorted by id.
// Conservative: a chunk whose box only touches the frustum near a corner may be
// kept. Loads nothing.
std::vector<std::int64_t> chunks_in_view(const RenderCamera& camera, const ChunkSource& source);

// The same chunks with their references (bounds, triangle counts), sorted by id.
std::vector<ChunkRef> chunk_refs_in_view(const RenderCamera& camera, const ChunkSource& source);

}  // namespace cellbake

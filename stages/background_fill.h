// Colours for a cube face's background pixels (those without a surface),
// pulled from the covered pixels around them. A textured depth mesh samples its
// texture bilinearly, so texels just outside a silhouette bleed into its edge
// pixels; left black they draw a dark halo around every far-field outline (and
// cost JPEG bits in ringing). Filled smoothly they are invisible and cheap.
#pragma once

#include "stages/cube_map.h"

namespace cellbake {

// Replaces the colour of every background pixel (depth not finite) of `face`
// by a smooth extension of the covered pixels' colours (push-pull over an
// image pyramid: averages of covered pixels going down, filled back up), alpha
// 0 kept, so coverage still reads from depth and alpha. Covered pixels are not
// changed. A face without covered pixels is left as it is. Deterministic.
void fill_background_colors(CubeFace& face);

// The same for every pixel `mesh` (the face's textured depth mesh as drawn)
// does not read (stages/texel_footprint.h) — background, and covered pixels
// no triangle textures from, e.g. in tiles drawn as exact geometry — so the
// image codec spends its bytes on the pixels a viewer can show. The pixels
// the mesh reads keep their colours exactly.
void fill_unread_colors(CubeFace& face, const FaceMesh& mesh);

}  // namespace cellbake

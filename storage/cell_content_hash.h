// The content hash of a cell row: XXH3-128 over everything a viewer reads
// (cull box, near-field list, samples, face images and meshes), nothing about
// timing. `bake` stamps it into cells.content_hash; `status --check` and
// `merge` recompute it from the stored rows to find damaged cells.
#pragma once

#include <string>

#include "storage/cell_db.h"

namespace cellbake {

// Hex digest of `row`'s content (id, cull_half_size, near_triangles,
// near_chunks, and per sample in order: index, eye, parent, void_after, pixel
// counts, and per face: face, image_format, image and mesh bytes; then the
// far geometry list, each row's level only when it is not 0 so cells baked
// before levels keep their hash, and per-face far choice when there are any). Ignores
// status, error, hashes, bounds, stage and sample seconds. Deterministic.
std::string cell_content_hash(const CellRow& row);

}  // namespace cellbake

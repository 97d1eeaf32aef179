// Console output for ingest: a progress callback and the closing summary.
#pragma once

#include <string>

#include "pipeline/ingest.h"

namespace cellbake {

// A ProgressCallback that prints phase changes and write progress to stderr
// (an empty one under -q: runner/console.h).
ProgressCallback ingest_progress();

// Prints the ingest summary (counts, skips, chunks, bounds, timings,
// throughput), or (json) one JSON object with the same figures: store,
// triangles_read, triangles_stored, polygons_triangulated, skipped_degenerate,
// skipped_duplicate, chunks, vertices, bounds {min, max}, seconds {read,
// chunk, write, total}, up, up_source, up_from_geometry {axis, evidence},
// textures, texture_bytes, warnings (texture, input and up-axis warnings, one
// string each), vertex_colour_notes, content_hash.
void print_ingest_summary(const IngestReport& r, const std::string& store, bool json = false);

}  // namespace cellbake

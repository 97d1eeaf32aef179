// `cellbake status STORE.db`: what a geometry store holds, for looking at a
// model before baking it (bounds, size, triangles, chunks, materials,
// textures, the recorded up axis, the source files).
#pragma once

#include <cstdio>

#include <nlohmann/json.hpp>

#include "storage/geometry_store.h"

namespace cellbake {

// The store's summary as JSON: kind, path, bounds {min, max}, size (extent per
// axis), triangles, vertices, chunks, materials, textures, units, up ("z" |
// "y" | null when not recorded), up_source, content_hash, sources [{path,
// bytes, triangles}].
nlohmann::json store_status_json(const GeometryStore& store);

// The same as lines of text on `out`: a first line naming the store, then
// print_store_facts.
void print_store_status(const GeometryStore& store, std::FILE* out);

// The facts alone (bounds, size, counts, up axis, content hash, sources), one
// per line, for reports that name the store their own way (`cellbake info`).
void print_store_facts(const GeometryStore& store, std::FILE* out);

}  // namespace cellbake

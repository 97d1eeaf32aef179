// `cellbake info`'s report on a geometry store: the store's facts (as
// `status` prints them), the up axis it uses and why, the floors found by
// casting rays down over a grid (stages/model_analysis/floor_finder.h) and a suggested bake —
// a region at eye height over the main floor, a cell size, the near budget the
// bake would use and an estimated time — as command lines to run. Model units
// are taken as metres (eye height 1.7, cells of 2-4).
#pragma once

#include <string>

#include "pipeline/ingest.h"
#include "storage/geometry_store.h"

namespace cellbake {

// Set when the store was just read from a model file into a temporary store:
// the report then names the model and prints the `cellbake ingest` line that
// keeps a store, before the `cellbake bake` line.
struct InfoModelFile {
  std::string model;       // the model file as given
  std::string store_name;  // the store the ingest line writes: NAME.store.db, in the current directory
  std::size_t chunk_triangles = 0;  // the ingest line's --chunk-triangles (0: ingest's default, not printed)
  IngestReport ingest;              // what reading it found (up axis and why, warnings)
  double seconds = 0;               // how long reading it took
};

// The far field is made of whole chunks outside a cell's cull box, so a store
// of few chunks has almost none. Returns a --chunk-triangles value that gives
// a store of `summary.triangles` at least 16 chunks (a power of two, >= 16), or
// 0 when it has that many already.
std::size_t suggested_chunk_triangles(const StoreSummary& summary);

// Prints the report on `store` to stdout, as text or (json) one JSON object:
// store_status_json's fields plus up_used, up_used_source, floor_search,
// floors[], suggested{} (null without floors) and, for a model file, kind
// "model_file", path (the model), store (store_name), ingest (the command),
// ingest_seconds and warnings[]; for a store of few chunks,
// chunk_triangles_hint (suggested_chunk_triangles). `up` ("", "z", "y"): the axis to use instead
// of the recorded one (for a model file it was given to the ingest already).
// Reads every chunk twice at most (floors; the up axis when none is recorded).
void print_info(const GeometryStore& store, const InfoModelFile* model, const std::string& up, bool json);

}  // namespace cellbake

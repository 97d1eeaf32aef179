// The checks of a cell database that need the pipeline's knowledge (issue
// #41 item 3, #37 item 3): its meta values parsed, finite and in range (the
// config text read back with the config file's rules, cell size, up axis,
// store hash, counts), and the context check_cell (storage/cell_check.h)
// compares cells with: each cell's place in the configuration's grid and the
// geometry store the database was baked from. Used by `status --check` and
// `merge`.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "storage/cell_check.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"

namespace cellbake {

struct MetaProblem {
  std::string key;     // the meta key ("config", "cell_size", ...)
  std::string reason;  // e.g. "view.far_budget: 'view.far_budget' must be an integer"
};

// The meta values a reader uses: `config` (every line a known key with a
// value of its type and range, regions six finite numbers; config_from_description),
// `cell_size` (a positive number equal to the config's cells.size), `up` (z
// or y, the config's), `store_hash` (a word of printable ASCII), `cells_total` and
// `cells_selected` (decimal counts). A key that is absent is not a problem
// (databases of older bakes, test fixtures). Never throws for a bad value.
std::vector<MetaProblem> check_database_meta(const CellDb& db);

// A check context and what it holds: `place` from the database's config
// (unset when it names no regions or does not parse), `store` the geometry
// store at `store_path` (default: the database's meta `store`) when it exists
// and its content hash is meta `store_hash`; otherwise none, and `note` says
// why the store-aware checks are skipped. With the store and a config that
// parses, `resample` samples the model as the cells' bake did, so face images
// are compared with it.
struct CellCheckSetup {
  std::unique_ptr<GeometryStore> store;
  CellCheckContext context;
  std::string note;
};
CellCheckSetup cell_check_setup(const CellDb& db, const std::filesystem::path& store_path = {});

}  // namespace cellbake

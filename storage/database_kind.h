// Which of cellbake's two SQLite files a path holds, from its meta `kind`:
// commands that take either (status, render) pick their path with it.
#pragma once

#include <filesystem>

namespace cellbake {

enum class DatabaseKind {
  geometry_store,  // meta kind 'cellbake-geometry-store' (ingest's output)
  other,           // anything else: a cell database, or a file the cell-database opener will refuse with its reason
};

// Reads the meta `kind` of the SQLite file at `path` (read-only). Never
// throws: a missing or unreadable file, or one without a meta table, is `other`.
DatabaseKind database_kind(const std::filesystem::path& path);

}  // namespace cellbake

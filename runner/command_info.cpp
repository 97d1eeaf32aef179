// `cellbake info PATH [--up z|y] [--json]`: what a file is and, for a geometry
// store or a model file, a suggested bake (runner/info_report.h). A model file
// is ingested as `cellbake ingest` would (quietly, once) into a temporary
// store under $TMPDIR that is removed again, also on error; the report then
// prints the ingest line that keeps a store before the bake line.
#include <stdlib.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "pipeline/ingest.h"
#include "runner/commands.h"
#include "runner/console.h"
#include "runner/info_report.h"
#include "runner/parallel.h"
#include "storage/database_kind.h"
#include "storage/geometry_store.h"

namespace cellbake {
namespace {

bool is_sqlite_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char header[16] = {};
  in.read(header, sizeof header);
  return in.gcount() == 16 && std::string(header, 15) == "SQLite format 3";
}

std::string shell_word(const std::string& path) {
  return path.find_first_of(" '\"$\\") == std::string::npos ? path : "'" + path + "'";
}

// A fresh directory $TMPDIR/cellbake-info-XXXXXX, removed with everything in it.
class TemporaryDirectory {
 public:
  TemporaryDirectory() {
    std::string name = (std::filesystem::temp_directory_path() / "cellbake-info-XXXXXX").string();
    if (!::mkdtemp(name.data()))
      throw std::runtime_error("cannot create a temporary directory in " +
                               std::filesystem::temp_directory_path().string());
    path_ = name;
  }
  ~TemporaryDirectory() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// NAME.store.db for MODEL = NAME.ext[.gz], in the current directory.
std::string store_name_for(const std::string& model) {
  std::string stem = std::filesystem::path(model).filename().string();
  if (const auto dot = stem.find('.'); dot != std::string::npos && dot > 0) stem.resize(dot);
  return stem + ".store.db";
}

// Ingests the model into a temporary store (the ingest command's defaults,
// `up` if given, no progress) and reports on that store. A small model that
// makes fewer than 16 chunks is read again with smaller ones (at most 64 k
// triangles: quick), so the store the printed ingest line writes is the one
// looked at and its bake has a far field.
void info_model_file(const std::string& path, const std::string& up, bool json) {
  InfoModelFile model;
  model.model = path;
  model.store_name = store_name_for(path);
  if (!quiet_output())
    std::fprintf(stderr, "info: reading %s into a temporary geometry store...\n", path.c_str());
  const TemporaryDirectory dir;
  std::filesystem::path store_path = dir.path() / model.store_name;
  IngestParams params;
  params.up = up;
  const auto start = std::chrono::steady_clock::now();
  model.ingest = ingest_models({path}, store_path, params, tbb_parallel_for());
  if (const std::size_t c = suggested_chunk_triangles(GeometryStore(store_path).summary())) {
    model.chunk_triangles = params.max_chunk_triangles = c;
    store_path = dir.path() / ("small-chunks." + model.store_name);
    model.ingest = ingest_models({path}, store_path, params, tbb_parallel_for());
  }
  model.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const GeometryStore store(store_path);  // closed before `dir` is removed
  print_info(store, &model, up, json);
}

}  // namespace

void add_info_command(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  auto up = std::make_shared<std::string>();
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand("info",
                                     "Look at a model before baking: its facts, up axis, floors and a "
                                     "suggested bake (ingest and bake lines)");
  cmd->add_option(
         "path", *path,
         "Model file (read into a temporary store in $TMPDIR, removed again), geometry store (ingest's "
         "output) or cell database")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--up", *up,
                  "Up axis to use: z or y (default: the store's recorded axis; for a model file what ingest "
                  "records: the format's convention, else what the geometry shows; else z)")
      ->check(CLI::IsMember({"z", "y"}));
  cmd->add_flag("--json", *json, "Print the same as one JSON object");
  cmd->footer(
      "Examples:\n  cellbake info house.obj               # reads it: floors, suggested ingest and bake "
      "lines\n"
      "  cellbake info house.store.db          # the same for a store ingest wrote\n"
      "  cellbake info house.glb --json");
  cmd->callback([path, up, json] {
    if (database_kind(*path) == DatabaseKind::geometry_store) {
      const GeometryStore store(*path);
      return print_info(store, nullptr, *up, *json);
    }
    if (is_sqlite_file(*path)) {
      if (*json)
        std::printf("%s\n", nlohmann::json{{"kind", "cell_database"},
                                           {"path", *path},
                                           {"see", "cellbake status --json " + shell_word(*path)}}
                                .dump(2)
                                .c_str());
      else
        std::printf("%s: a cell database (or another SQLite file): `cellbake status %s` describes it\n",
                    path->c_str(), shell_word(*path).c_str());
      return;
    }
    info_model_file(*path, *up, *json);
  });
}

}  // namespace cellbake

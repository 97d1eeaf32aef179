// Viewer-side decode time of whole cells on one core: for each done cell of a
// cell database, decode_cell (viewer/decoded_cell.h) with the cell's geometry
// store: every face image and face mesh of its samples, and the far pieces
// cut out of their stored chunks or loaded as their simplified levels. Prints
// the median and worst milliseconds per cell (best of --repeat, so the store's
// chunk cache is warm; the first, cold decode is printed too), the stored
// bytes by kind and the far geometry rows that draw a level (issue #35).
//
//   bench_cell_decode CELLS.db [--store STORE.db] [--repeat 5]
//
// Not a Google Benchmark program: it reads a database.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bench_program.h"
#include "runner/verify/verify_report.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "viewer/decoded_cell.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

int run(int argc, char** argv) {
  CLI::App app("Viewer-side decode time of whole cells on one core");
  std::string database, store_path;
  int repeat = 5;
  app.add_option("database", database, "Cell database")->required();
  app.add_option("--store", store_path, "Geometry store (default: the one the database names)");
  app.add_option("--repeat", repeat, "Decodes per cell (the best is reported)")->check(CLI::Range(1, 1000));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  const CellDb db(database, CellDb::Mode::read_only);
  if (store_path.empty()) store_path = db.meta("store").value_or("");
  if (store_path.empty()) throw std::invalid_argument(database + " names no store: pass --store");
  const GeometryStore store(store_path);
  std::vector<double> per_cell, cold;
  std::uint64_t colour = 0, mesh = 0, far = 0, far_triangles = 0, level_rows = 0, level_triangles = 0;
  for (std::int64_t id : db.cell_ids()) {
    const std::optional<CellRow> row = db.get_cell(id);
    if (!row || row->status != "done") continue;
    double best = 1e300;
    for (int r = 0; r < repeat; ++r) {
      const auto t0 = Clock::now();
      const DecodedCell cell = decode_cell(*row, &store);
      const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (r == 0) cold.push_back(ms);
      best = std::min(best, ms);
      if (cell.id != id) throw std::logic_error("decoded the wrong cell");
    }
    per_cell.push_back(best);
    for (const SampleRow& s : row->samples)
      for (const FaceRow& f : s.faces) colour += f.image.size(), mesh += f.mesh.size();
    for (const FarGeometryRow& g : row->far_geometry) {
      far += g.geometry.size();
      // Bytes per far triangle: of the chunks' own triangles (a level row stores no bytes).
      (g.level == 0 ? far_triangles : level_triangles) += g.triangles;
      level_rows += g.level != 0;
    }
  }
  if (per_cell.empty()) throw std::runtime_error("no done cells");
  const double n = double(per_cell.size());
  std::printf("%zu cells: decode ms per cell median %.2f, worst %.2f (first, cold: median %.2f, worst %.2f); "
              "per cell %.1f KB colour, %.1f KB mesh, %.1f KB far geometry (%.2f B per far triangle); "
              "%llu far rows drawing a simplified level (%llu triangles)\n",
              per_cell.size(), median_of(per_cell), *std::max_element(per_cell.begin(), per_cell.end()), median_of(cold),
              *std::max_element(cold.begin(), cold.end()), colour / 1024.0 / n, mesh / 1024.0 / n, far / 1024.0 / n,
              far_triangles ? double(far) / double(far_triangles) : 0.0, (unsigned long long)level_rows,
              (unsigned long long)level_triangles);
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_cell_decode", cellbake::run, argc, argv);
}

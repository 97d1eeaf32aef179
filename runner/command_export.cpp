// `cellbake export DB (--cell ID | --cells SEL) [--store S] --out FILE.glb
//  [--compress] [--json]`: view cells as one glTF 2.0 binary file for other
// viewers (Blender, three.js, game engines): near field, exact far geometry
// and textured depth meshes with their images, lit as the bake lit them
// (pipeline/export/cell_gltf_export.h).
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string_view>

#include "pipeline/cell_grid.h"
#include "pipeline/export/cell_gltf_export.h"
#include "runner/commands.h"
#include "runner/console.h"
#include "storage/cell_db.h"
#include "storage/database_kind.h"
#include "storage/geometry_store.h"
#include "storage/output_file.h"
#include "storage/store_check.h"
#include "viewer/baked_config_text.h"
#include "viewer/cell_index.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

struct Options {
  std::string database, cells, store, out;
  std::int64_t cell = 0;
  bool single = false;  // --cell given
  bool json = false;
  GltfExportOptions exporter;
};

// The ids of the cells to export, in id order: `--cell` (which must be a done
// cell of the database) or the done cells `--cells` selects.
std::vector<std::int64_t> chosen_cells(const Options& opt, const CellDb& db) {
  const CellIndex index(db);
  if (opt.single) {
    const CellEntry* e = index.find(opt.cell);
    if (!e) throw std::runtime_error("cell " + std::to_string(opt.cell) + " is not in " + opt.database);
    if (!e->done) throw std::runtime_error("cell " + std::to_string(opt.cell) + " of " + opt.database + " is not baked (failed or unreadable)");
    return {opt.cell};
  }
  std::vector<CellSpec> specs;
  for (const CellEntry& e : index.cells())
    if (e.done) specs.push_back({e.id, 0, e.gx, e.gy, e.gz, e.bounds});
  if (specs.empty()) throw std::runtime_error(opt.database + " has no baked cells");
  std::vector<std::int64_t> ids;
  for (const CellSpec& s : select_cells(specs, opt.cells)) ids.push_back(s.id);
  if (ids.empty()) throw std::runtime_error("--cells " + opt.cells + " selects no baked cell of " + opt.database);
  return ids;
}

void run_export(const Options& opt) {
  const auto start = std::chrono::steady_clock::now();
  if (database_kind(opt.database) == DatabaseKind::geometry_store)
    throw std::invalid_argument(opt.database + " is a geometry store (not baked): export needs a cell database");
  const CellDb db(opt.database, CellDb::Mode::read_only);
  std::filesystem::path store_path = opt.store;
  if (store_path.empty()) {
    const auto named = db.meta("store");
    if (!named) throw std::runtime_error(opt.database + " has no meta 'store' (not a cell database?); give --store");
    store_path = *named;
  }
  if (!std::filesystem::exists(store_path))
    throw std::runtime_error("geometry store " + store_path.string() + " (of " + opt.database +
                             ") does not exist; give --store");
  const GeometryStore store(store_path);
  if (const std::string mismatch = store_mismatch(db.path(), db.meta("store_hash"), store.path(), store.summary().content_hash);
      !mismatch.empty())
    std::fprintf(stderr, "warning: %s\n", mismatch.c_str());
  const InputFiles inputs{opt.database, store.path()};
  check_output_target(opt.out, inputs);  // before the work

  const std::vector<std::int64_t> ids = chosen_cells(opt, db);
  std::vector<CellRow> rows;
  std::vector<DecodedCell> decoded;
  rows.reserve(ids.size());
  decoded.reserve(ids.size());
  std::uint64_t stored_bytes = 0;
  for (std::int64_t id : ids) {
    std::optional<CellRow> row = db.get_cell(id, true);
    if (!row) throw std::runtime_error("cell " + std::to_string(id) + " is not in " + opt.database);
    decoded.push_back(decode_cell(*row, &store));  // names the cell
    stored_bytes += row->bytes;
    rows.push_back(std::move(*row));
  }
  std::vector<CellToExport> cells;
  for (std::size_t k = 0; k < ids.size(); ++k) cells.push_back({&rows[k], &decoded[k]});

  GltfSceneContext context;
  const std::string config = db.meta("config").value_or("");
  context.up = up_axis(db.meta("up").value_or("z"));
  context.lights = shading_lights(shading_of_config_text(config), context.up);
  context.database_name = std::filesystem::path(opt.database).filename().string();
  GltfExportStats stats;
  const std::vector<std::uint8_t> bytes = export_cells_glb(cells, store, context, opt.exporter, &stats);
  write_output_file(opt.out, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), inputs);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  if (opt.json) {
    nlohmann::json j{{"out", opt.out},
                     {"cells", ids},
                     {"bytes", stats.bytes},
                     {"cells_stored_bytes", stored_bytes},
                     {"store_chunks", stats.store_chunks},
                     {"store_chunk_bytes", stats.store_chunk_bytes},
                     {"meshes", stats.meshes},
                     {"images", stats.images},
                     {"images_reencoded", stats.images_reencoded},
                     {"image_bytes", stats.image_bytes},
                     {"near_triangles", stats.near_triangles},
                     {"far_geometry_triangles", stats.far_geometry_triangles},
                     {"depth_mesh_triangles", stats.depth_mesh_triangles},
                     {"depth_mesh_triangles_out", stats.depth_mesh_triangles_out},
                     {"compress", opt.exporter.compress},
                     {"seconds", seconds}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("%s: %zu cell%s, %llu bytes (%s), %.1f s\n", opt.out.c_str(), ids.size(), ids.size() == 1 ? "" : "s",
              (unsigned long long)stats.bytes, opt.exporter.compress ? "meshopt-compressed" : "uncompressed", seconds);
  std::printf("  near field %llu triangles, far geometry %llu, depth meshes %llu (%llu drawn with plain uvs), %zu meshes\n",
              (unsigned long long)stats.near_triangles, (unsigned long long)stats.far_geometry_triangles,
              (unsigned long long)stats.depth_mesh_triangles, (unsigned long long)stats.depth_mesh_triangles_out,
              stats.meshes);
  std::printf("  %zu images, %llu bytes (%llu re-encoded as JPEG/PNG)\n", stats.images,
              (unsigned long long)stats.image_bytes, (unsigned long long)stats.images_reencoded);
  const std::uint64_t stored_in_all = stored_bytes + stats.store_chunk_bytes;
  std::printf("  stored: the cells' rows %llu bytes and the %llu store chunks (or levels) they draw %llu bytes; "
              "the file is %.2fx that\n",
              (unsigned long long)stored_bytes, (unsigned long long)stats.store_chunks,
              (unsigned long long)stats.store_chunk_bytes,
              stored_in_all > 0 ? double(stats.bytes) / double(stored_in_all) : 0.0);
}

}  // namespace

void add_export_command(CLI::App& app) {
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Write view cells as a glTF 2.0 binary file (.glb) for other viewers (Blender, three.js, engines)");
  cmd->add_option("database", opt->database, "Cell database")->required();
  CLI::Option* cell = cmd->add_option("--cell", opt->cell, "The cell to export");
  CLI::Option* cells = cmd->add_option("--cells", opt->cells, "Cells to export into one file, e.g. 1-10,15 (a region)");
  cell->excludes(cells);
  cmd->add_option("--store", opt->store, "Geometry store (default: the one the database names)");
  cmd->add_option("--out", opt->out, "Output .glb file")->required();
  cmd->add_flag("--compress", opt->exporter.compress,
                "meshoptimizer-compressed streams (EXT_meshopt_compression) and AVIF/WebP face images kept as "
                "stored (EXT_texture_avif/webp): for web viewers (three.js, Babylon.js); Blender cannot read it");
  cmd->add_option("--uv-tolerance", opt->exporter.uv_tolerance_px,
                  "Largest texture error of depth-mesh edges drawn with plain texture coordinates, face pixels")
      ->check(CLI::Range(0.01, 100.0))
      ->capture_default_str();
  cmd->add_option("--position-tolerance", opt->exporter.position_tolerance,
                  "Largest position error of chunk geometry, model units: each mesh takes the fewest bits (8..16) "
                  "within it (0: 16 bits)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--position-tolerance-per-distance", opt->exporter.position_tolerance_per_distance,
                  "... and no less than this fraction of the chunk's distance from the nearest exported cell "
                  "(0: the fixed tolerance everywhere)")
      ->check(CLI::Range(0.0, 0.1))
      ->capture_default_str();
  cmd->add_option("--depth-mesh-tolerance", opt->exporter.depth_mesh_tolerance,
                  "Largest position error of a depth mesh, as a fraction of its nearest vertex's distance from "
                  "the sample eye (0: 16 bits)")
      ->check(CLI::Range(0.0, 0.1))
      ->capture_default_str();
  cmd->add_option("--uv-subpixels", opt->exporter.uv_subpixels,
                  "Depth-mesh texture coordinates on a grid of this many steps per face pixel "
                  "(KHR_texture_transform); 0: normalised 16-bit")
      ->check(CLI::Range(0, 64))
      ->capture_default_str();
  cmd->add_option("--jpeg-quality", opt->exporter.jpeg_quality,
                  "Quality of images re-encoded as JPEG (faces stored as AVIF/WebP/JPEG XL, textures)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--color-bits", opt->exporter.color_bits, "Bits of the linear vertex colours: 8 or 16")
      ->check(CLI::IsMember({8, 16}))
      ->capture_default_str();
  cmd->add_flag("--normals", opt->exporter.normals,
                "Write chunk normals (int8) for relighting elsewhere; the unlit materials do not use them");
  cmd->add_flag("--json", opt->json, "Print the summary as JSON");
  cmd->callback([opt, cell, cells] {
    if (cell->count() == 0 && cells->count() == 0) throw std::invalid_argument("give --cell ID or --cells SEL");
    opt->single = cell->count() > 0;
    run_export(*opt);
  });
}

}  // namespace cellbake

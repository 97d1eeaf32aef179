// `cellbake ingest MODEL... --store STORE.db`
#include <CLI/CLI.hpp>

#include "pipeline/ingest.h"
#include "runner/commands.h"
#include "runner/ingest_summary.h"
#include "runner/parallel.h"

namespace cellbake {

void add_ingest_command(CLI::App& app) {
  struct Options {
    std::vector<std::string> models;
    std::string store;
    std::size_t chunk = 4096;
    std::vector<double> translate;
    std::string units = "m";
    int max_texture_size = 2048;
    bool allow_outside_paths = false;
    bool import_in_process = false;
    double import_memory_gb = 0;
    double import_seconds = 3600;
    std::string up;
    bool json = false;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "ingest", "Import model files (OBJ, PLY, glTF/GLB, OFF, STL, .gz, anything assimp reads) into a geometry store");
  cmd->add_option("models", opt->models, "Model files")->required();
  cmd->add_option("--store", opt->store, "Geometry store to write (replaced only on success)")->required();
  cmd->add_option("--chunk-triangles", opt->chunk, "Maximum triangles per chunk")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t(16), std::size_t(1) << 20));
  cmd->add_option("--translate", opt->translate, "Offset X,Y,Z added to every coordinate")->delimiter(',')->expected(3);
  cmd->add_option("--units", opt->units, "Unit name recorded in the store")->capture_default_str();
  cmd->add_option("--max-texture-size", opt->max_texture_size,
                  "Longest texture side kept in the store; larger textures are halved until they fit")
      ->capture_default_str()
      ->check(CLI::Range(1, 16384));
  cmd->add_flag("--allow-outside-paths", opt->allow_outside_paths,
                "Read files the models name (mtllib, map_Kd, glTF buffers and images) outside the model's folder; "
                "by default such references are skipped with a warning");
  cmd->add_flag("--import-in-process", opt->import_in_process,
                "Run assimp's import in this process; by default formats read through assimp (glTF, COLLADA, FBX, "
                "X3D, ...) are imported in a child process, so that a crash or a runaway import is an error "
                "naming the file");
  cmd->add_option("--import-memory-gb", opt->import_memory_gb,
                  "Memory an assimp import may use beyond the process's own, in GiB (default: half the machine's "
                  "memory); more is an error naming the file")
      ->check(CLI::Range(0.01, 1e6));
  cmd->add_option("--import-seconds", opt->import_seconds,
                  "Seconds an assimp import may take before it is stopped with an error naming the file")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1e7));
  cmd->add_option("--up", opt->up,
                  "The model's up axis, recorded in the store for bake: z or y (default: what the format says: "
                  "glTF, IFC and COLLADA y, FBX its UpAxis; for OBJ/PLY/OFF/STL what the geometry shows (large "
                  "horizontal planes), else none and bake assumes z; a sure geometry that disagrees is a warning)")
      ->check(CLI::IsMember({"z", "y"}));
  cmd->add_flag("--json", opt->json, "Print the summary as JSON (progress still goes to stderr; -q hides it)");
  cmd->callback([opt] {
    std::vector<std::filesystem::path> models(opt->models.begin(), opt->models.end());
    IngestParams params;
    params.max_chunk_triangles = opt->chunk;
    params.units = opt->units;
    params.max_texture_size = opt->max_texture_size;
    params.allow_outside_paths = opt->allow_outside_paths;
    params.up = opt->up;
    params.import_in_child_process = !opt->import_in_process;
    if (opt->import_memory_gb > 0) params.import_memory_bytes = std::uint64_t(opt->import_memory_gb * double(1 << 30));
    params.import_seconds = opt->import_seconds;
    if (opt->translate.size() == 3) params.translate = {opt->translate[0], opt->translate[1], opt->translate[2]};
    const IngestReport r = ingest_models(models, opt->store, params, tbb_parallel_for(), ingest_progress());
    print_ingest_summary(r, opt->store, opt->json);
  });
}

}  // namespace cellbake

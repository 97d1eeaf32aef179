// `cellbake generate KIND --triangles N --seed S --out FILE [--store STORE]`
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>

#include "pipeline/ingest.h"
#include "pipeline/scenes/scene_ply_writer.h"
#include "runner/commands.h"
#include "runner/ingest_summary.h"
#include "runner/parallel.h"

namespace cellbake {

void add_generate_command(CLI::App& app) {
  struct Options {
    std::string kind;
    std::uint64_t triangles = 2'000'000;
    std::uint64_t seed = 1;
    std::string out;
    std::string store;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand("generate", "Generate a procedural test scene (plant, house, city) as binary PLY");
  cmd->add_option("kind", opt->kind, "Scene kind: plant | house | city")
      ->required()
      ->check(CLI::IsMember({"plant", "house", "city"}));
  cmd->add_option("--triangles,-n", opt->triangles, "Target triangle count, 100 k to 2 G (result within ~10 %)")
      ->capture_default_str()
      ->check(CLI::Range(std::uint64_t(100'000), std::uint64_t(2'000'000'000)));
  cmd->add_option("--seed,-s", opt->seed, "Random seed (same seed, same scene)")->capture_default_str();
  cmd->add_option("--out,-o", opt->out, "Output PLY file")->required();
  cmd->add_option("--store", opt->store, "Also ingest the scene into this geometry store");
  cmd->callback([opt] {
    SceneParams params;
    params.kind = parse_scene_kind(opt->kind);
    params.target_triangles = opt->triangles;
    params.seed = opt->seed;
    const auto t0 = std::chrono::steady_clock::now();
    const SceneSummary s = generate_scene_to_ply(params, opt->out);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("generated %s: %llu triangles, %llu vertices, bounds (%.2f %.2f %.2f)-(%.2f %.2f %.2f) m -> %s "
                "in %.2f s\n",
                opt->kind.c_str(), (unsigned long long)s.triangles, (unsigned long long)s.vertices, s.bounds.lo.x,
                s.bounds.lo.y, s.bounds.lo.z, s.bounds.hi.x, s.bounds.hi.y, s.bounds.hi.z, opt->out.c_str(), secs);
    if (!opt->store.empty()) {
      IngestParams ip;
      ip.up = "z";  // the generators build z-up scenes
      const IngestReport r = ingest_models({opt->out}, opt->store, ip, tbb_parallel_for(), ingest_progress());
      print_ingest_summary(r, opt->store);
    }
  });
}

}  // namespace cellbake

// `cellbake demo --out DIR`: the embedded default end to end: generate the
// default plant, ingest it, bake it with configs/plant-demo.toml (compiled in).
#include <CLI/CLI.hpp>
#include <cstdio>

#include "pipeline/bake_config.h"
#include "pipeline/embedded_configs.h"
#include "pipeline/ingest.h"
#include "pipeline/scenes/scene_ply_writer.h"
#include "runner/bake_command_options.h"
#include "runner/bake_runner.h"
#include "runner/commands.h"
#include "runner/console.h"
#include "runner/ingest_summary.h"
#include "runner/parallel.h"
#include "runner/verify/verify_runner.h"
#include "storage/geometry_store.h"

namespace cellbake {

void add_demo_command(CLI::App& app) {
  struct Options {
    std::string out = "out/demo";
    std::uint64_t triangles = 2'000'000;
    int threads = 0;
    std::vector<std::string> sets;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd =
      app.add_subcommand("demo", "Run the embedded default end to end: generate, ingest and bake the plant");
  cmd->add_option("--out,-o", opt->out, "Output folder")->capture_default_str();
  cmd->add_option("--triangles", opt->triangles, "Plant size in triangles")->capture_default_str();
  cmd->add_option("--threads", opt->threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
  cmd->add_option("--set", opt->sets, "Override a config key: section.key=value (repeatable)");
  cmd->callback([opt] {
    const std::filesystem::path out(opt->out);
    std::filesystem::create_directories(out);
    const std::filesystem::path ply = out / "plant.ply", store = out / "plant.store.db";
    SceneParams sp;
    sp.kind = SceneKind::plant;
    sp.target_triangles = opt->triangles;
    sp.seed = 1;
    // Regenerate and re-ingest only when the store is missing or of another size.
    bool fresh = std::filesystem::exists(store);
    if (fresh) {
      try {
        GeometryStore existing(store);
        const StoreSummary s = existing.summary();
        fresh = s.triangles > opt->triangles * 8 / 10 && s.triangles < opt->triangles * 12 / 10;
      } catch (const std::exception&) {
        fresh = false;
      }
    }
    if (!fresh) {
      std::printf("[demo] generating plant (%llu triangles) -> %s\n", (unsigned long long)opt->triangles,
                  ply.c_str());
      const SceneSummary s = generate_scene_to_ply(sp, ply);
      std::printf("[demo] %llu triangles; ingesting -> %s\n", (unsigned long long)s.triangles, store.c_str());
      IngestParams ingest;
      ingest.up = "z";  // the generators build z-up scenes
      const IngestReport r = ingest_models({ply}, store, ingest, tbb_parallel_for(), ingest_progress());
      print_ingest_summary(r, store.string());
    } else {
      std::printf("[demo] reusing geometry store %s\n", store.c_str());
    }
    BakeConfig config = parse_bake_config(embedded_plant_demo_config(), out / "plant-demo.toml");
    for (const auto& s : opt->sets) apply_override(config, s);
    validate_bake_config(config);
    BakeOptions bo;
    bo.threads = opt->threads;
    bo.quiet = quiet_output();
    bo.verbose = verbose_output();
    std::printf("[demo] baking %s\n", config.database.c_str());
    const BakeSummary s = run_bake(config, bo);
    print_bake_summary(s, config);
    if (s.cells_failed > 0) throw std::runtime_error(std::to_string(s.cells_failed) + " cell(s) failed");

    // Last step: the verify report (impostor vs ground truth) of the demo bake.
    VerifyOptions vo;
    vo.views_per_cell = 4;       // random views: the headline
    vo.reference_views = false;  // the sample points' views are the reference
    vo.width = 256;
    vo.height = 192;
    vo.threads = opt->threads;
    vo.walk_seconds = 8;  // a short walk video in the report
    vo.quiet = quiet_output();
    vo.verbose = verbose_output();
    const std::filesystem::path report = out / "report";
    std::printf("[demo] verifying %s -> %s\n", config.database.c_str(), report.c_str());
    const VerifySummary v = run_verify(config.database, report, vo);
    std::printf("[demo] %llu views, median PSNR %.2f dB over random views, %.1f s\n[demo] report: %s\n",
                (unsigned long long)v.views_rendered, v.psnr_median_db, v.seconds,
                std::filesystem::absolute(v.report_html).c_str());
  });
}

}  // namespace cellbake

// `cellbake merge OUT.db SHARD.db...`: combine the shard databases of a
// distributed bake into one cell database (see runner/merge_shards.h).
#include <CLI/CLI.hpp>

#include <cstdio>

#include <nlohmann/json.hpp>

#include "runner/commands.h"
#include "runner/merge_shards.h"

namespace cellbake {

void add_merge_command(CLI::App& app) {
  struct Options {
    std::string out;
    std::vector<std::string> shards;
    bool json = false;
    bool check_images = false;
  };
  auto opt = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "merge", "Merge shard databases of a distributed bake into one (idempotent; a missing shard is skipped with a warning)");
  cmd->add_option("out", opt->out, "Merged cell database (created, or added to)")->required();
  cmd->add_option("shards", opt->shards, "Shard cell databases")->required();
  cmd->add_flag("--json", opt->json, "Print the summary as JSON");
  cmd->add_flag("--check-images", opt->check_images,
                "Also compare every face image with the model resampled at its sample's eye, as `status --check` "
                "does (a low-resolution resample per sample: on the 82 M plant more than the merge itself)");
  cmd->callback([opt] {
    std::vector<std::filesystem::path> shards(opt->shards.begin(), opt->shards.end());
    const MergeSummary s =
        merge_shards(opt->out, shards, [](const std::string& w) { std::fprintf(stderr, "warning: %s\n", w.c_str()); },
                     opt->check_images);
    if (opt->json) {
      nlohmann::json missing = nlohmann::json::array();
      for (const auto& m : s.missing_shards) missing.push_back(m);
      const nlohmann::json j{{"database", opt->out},          {"shards_merged", s.shards_merged},
                             {"missing_shards", missing},      {"cells_copied", s.cells_copied},
                             {"cells_unchanged", s.cells_unchanged}, {"cells_kept_done", s.cells_kept_done},
                             {"cells_done", s.cells_done},     {"cells_failed", s.cells_failed},
                             {"cells_total", s.cells_total}};
      std::printf("%s\n", j.dump(2).c_str());
      return;
    }
    std::printf("merge %s: %llu shard(s) merged, %zu missing; %llu cells copied, %llu unchanged, %llu failed cells "
                "not copied over done ones; now %llu done, %llu failed of %llu\n",
                opt->out.c_str(), (unsigned long long)s.shards_merged, s.missing_shards.size(),
                (unsigned long long)s.cells_copied, (unsigned long long)s.cells_unchanged,
                (unsigned long long)s.cells_kept_done, (unsigned long long)s.cells_done,
                (unsigned long long)s.cells_failed, (unsigned long long)s.cells_total);
  });
}

}  // namespace cellbake

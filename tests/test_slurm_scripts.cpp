// The Slurm batch scripts of `cellbake submit`, run by bash with a stand-in
// for the cellbake binary (no Slurm needed), and `submit --dry-run`.
#include <gtest/gtest.h>

#include "runner/slurm_scripts.h"
#include "test_support.h"

namespace cellbake {
namespace {

// Runs `script` with bash under the given environment assignments; stdout.
std::string run_script(const test::TempDir& dir, const std::string& script, const std::string& env) {
  test::write_text(dir / "job.sh", script);
  FILE* pipe = popen(("env " + env + " bash " + (dir / "job.sh").string() + " 2>&1").c_str(), "r");
  std::string out;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, pipe)) > 0;) out.append(buf, n);
  pclose(pipe);
  return out;
}

// A job whose "binary" prints its arguments one per line, with awkward paths.
SlurmBakeJob echo_job(const test::TempDir& dir) {
  test::write_text(dir / "args.sh", "#!/bin/sh\nfor a in \"$@\"; do echo \"[$a]\"; done\n");
  SlurmBakeJob job;
  job.binary = (dir / "args.sh").string();
  job.bake_args = {"/data/my configs/it's.toml", "--set", "near.budget=500"};
  job.shards = 4;
  job.out_dir = "/scratch/out dir";
  job.merged_db = "/scratch/merged.db";
  job.workdir = "/scratch";
  job.time = "01:00:00";
  return job;
}

TEST(SlurmScripts, ArrayTaskBakesItsShardWithQuotedArguments) {
  test::TempDir dir;
  const SlurmBakeJob job = echo_job(dir);
  std::filesystem::permissions(dir / "args.sh", std::filesystem::perms::owner_all, std::filesystem::perm_options::add);
  const std::string script = array_script(job);
  EXPECT_NE(script.find("#SBATCH --array=0-3\n"), std::string::npos) << script;
  EXPECT_NE(script.find("#SBATCH --time=01:00:00\n"), std::string::npos) << script;
  EXPECT_EQ(script.find("--partition"), std::string::npos) << script;
  EXPECT_EQ(run_script(dir, script, "SLURM_ARRAY_TASK_ID=2 SLURM_CPUS_PER_TASK=3"),
            "[bake]\n[/data/my configs/it's.toml]\n[--set]\n[near.budget=500]\n[--shard]\n[2/4]\n[--out]\n"
            "[/scratch/out dir/shard_2.db]\n[--threads]\n[3]\n[--quiet]\n");
  // Without SLURM_CPUS_PER_TASK: one thread.
  EXPECT_NE(run_script(dir, script, "SLURM_ARRAY_TASK_ID=0").find("[--threads]\n[1]\n"), std::string::npos);
}

TEST(SlurmScripts, MergeJobListsEveryShard) {
  test::TempDir dir;
  const SlurmBakeJob job = echo_job(dir);
  std::filesystem::permissions(dir / "args.sh", std::filesystem::perms::owner_all, std::filesystem::perm_options::add);
  EXPECT_EQ(run_script(dir, merge_script(job), ""),
            "[merge]\n[/scratch/merged.db]\n[/scratch/out dir/shard_0.db]\n[/scratch/out dir/shard_1.db]\n"
            "[/scratch/out dir/shard_2.db]\n[/scratch/out dir/shard_3.db]\n");
  EXPECT_EQ(shard_db_path(job, 3), "/scratch/out dir/shard_3.db");
}

TEST(SlurmScripts, SubmitDryRunPrintsBothScriptsAndSubmitsNothing) {
  test::TempDir dir;
  test::write_text(dir / "bake.toml",
                   "[model]\nstore = \"room.store.db\"\n[[regions]]\nmin = [1, 1, 1.6]\nmax = [9, 9, 1.6]\n"
                   "[output]\ndatabase = \"cells.db\"\n");
  const auto r = test::run_cellbake("submit " + (dir / "bake.toml").string() +
                                    " --shards 3 --partition short --mem 2G --dry-run --set sample.face_size=32"
                                    " --set output.database=" + (dir / "elsewhere.db").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("#SBATCH --array=0-2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("#SBATCH --partition=short"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("#SBATCH --mem=2G"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'--set' 'sample.face_size=32'"), std::string::npos) << r.output;
  // Command-line paths are relative to the current directory; this one is absolute.
  EXPECT_EQ(r.output.find("'output.database=" + (dir / "elsewhere.db").string() + "'"), std::string::npos)
      << r.output;  // only for the merge
  EXPECT_NE(r.output.find("' merge '" + (dir / "elsewhere.db").string() + "'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find((dir / "elsewhere_shards/shard_2.db").string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("nothing submitted"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "elsewhere_shards"));
}

TEST(SlurmScripts, SubmitRejectsABadConfigBeforeSubmitting) {
  test::TempDir dir;
  test::write_text(dir / "bad.toml", "[cells]\nsize = -1\n");
  const auto r = test::run_cellbake("submit " + (dir / "bad.toml").string() + " --shards 2 --dry-run");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("bad.toml"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace cellbake

// The Slurm batch scripts of `cellbake submit`, run by bash with a stand-in
// for the cellbake binary (no Slurm needed), and `submit --dry-run`.
#include <gtest/gtest.h>

#include <sstream>

#include "runner/slurm_scripts.h"
#include "test_support.h"

namespace cellbake {
namespace {

// Runs `script` with bash under the given environment assignments; stdout.
std::string run_script(const test::TempDir& dir, const std::string& script, const std::string& env) {
  test::write_text(dir / "job.sh", script);
  return test::run_shell("env " + env + " bash " + (dir / "job.sh").string()).output;
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

std::string submit_help() { return test::run_cellbake("submit --help").output; }

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
            "[/scratch/out dir/shard_2.db]\n[--threads]\n[3]\n");
  // Without SLURM_CPUS_PER_TASK: as many threads as CPUs the task may use (not 1).
  const std::string nproc = run_script(dir, "nproc\n", "");
  EXPECT_NE(run_script(dir, script, "-u SLURM_CPUS_PER_TASK SLURM_ARRAY_TASK_ID=0").find("[--threads]\n[" + nproc.substr(0, nproc.find('\n')) + "]\n"),
            std::string::npos)
      << nproc;
  // Progress lines go to the task's log: no --quiet.
  EXPECT_EQ(script.find("--quiet"), std::string::npos) << script;
}

// The header lines of a script, in order ("#SBATCH ..." only).
std::vector<std::string> sbatch_lines(const std::string& script) {
  std::vector<std::string> lines;
  std::istringstream in(script);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("#SBATCH ", 0) == 0) lines.push_back(line.substr(8));
  return lines;
}

TEST(SlurmScripts, TasksAndMergeJobEachGetTheirOwnLimits) {
  test::TempDir dir;
  SlurmBakeJob job = echo_job(dir);
  job.partition = "batch";
  job.account = "proj42";
  job.qos = "long";
  job.mem = "16G";
  job.cpus_per_task = 8;
  job.sbatch_args = {"--gres=gpu:1", "--constraint=avx2"};
  job.merge_sbatch_args = {"--mail-type=END"};
  EXPECT_EQ(sbatch_lines(array_script(job)),
            (std::vector<std::string>{"--job-name=cellbake-bake", "--output=/scratch/out dir/logs/shard_%a.out",
                                      "--chdir=/scratch", "--partition=batch", "--account=proj42", "--qos=long",
                                      "--time=01:00:00", "--mem=16G", "--cpus-per-task=8", "--gres=gpu:1",
                                      "--constraint=avx2", "--array=0-3"}));
  // The merge job: same partition, account and QoS; its own small limits, one core, its own extras.
  EXPECT_EQ(sbatch_lines(merge_script(job)),
            (std::vector<std::string>{"--job-name=cellbake-merge", "--output=/scratch/out dir/logs/merge.out",
                                      "--chdir=/scratch", "--partition=batch", "--account=proj42", "--qos=long",
                                      "--time=01:00:00", "--mem=2G", "--mail-type=END"}));
  job.merge_time = "00:20:00";
  job.merge_mem = "";  // the cluster default
  EXPECT_EQ(sbatch_lines(merge_script(job))[6], "--time=00:20:00");
  EXPECT_EQ(merge_script(job).find("--mem"), std::string::npos);
}

TEST(SlurmScripts, ExtraSbatchOptionsAreCheckedBeforeTheyReachAScript) {
  EXPECT_NO_THROW(check_sbatch_arg("--gres=gpu:1", "--sbatch-arg"));
  EXPECT_NO_THROW(check_sbatch_arg("--exclusive", "--sbatch-arg"));
  EXPECT_NO_THROW(check_sbatch_arg("-C avx2", "--sbatch-arg"));
  for (const char* bad : {"", "gres=gpu:1", "--comment=a\n#SBATCH --array=0", "--array=0-9", "-a 1", "--output=x",
                          "--chdir=/", "--job-name=x", "--dependency=afterok:1", "--wrap=true"})
    EXPECT_THROW(check_sbatch_arg(bad, "--sbatch-arg"), std::invalid_argument) << bad;
  try {
    check_sbatch_arg("--array=1", "--merge-sbatch-arg");
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--merge-sbatch-arg '--array=1'"), std::string::npos) << e.what();
  }
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

TEST(SlurmScripts, SubmitDryRunTakesAccountQosCoresExtraOptionsAndMergeLimits) {
  test::TempDir dir;
  test::write_text(dir / "bake.toml",
                   "[model]\nstore = \"room.store.db\"\n[[regions]]\nmin = [1, 1, 1.6]\nmax = [9, 9, 1.6]\n"
                   "[output]\ndatabase = \"cells.db\"\n");
  const auto r = test::run_cellbake("submit " + (dir / "bake.toml").string() +
                                    " --shards 2 --account proj42 --qos long --time 4:00:00 --mem 8G --cpus-per-task 16"
                                    " --sbatch-arg=--gres=gpu:1 --sbatch-arg=--exclusive --merge-time 0:30:00"
                                    " --merge-mem 1G --merge-sbatch-arg=--mail-type=END --dry-run");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string merge_marker = "# " + (dir / "cells_shards/merge.sbatch").string();
  const std::size_t at = r.output.find(merge_marker);
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::string array = r.output.substr(0, at), merge = r.output.substr(at);
  for (const char* line : {"#SBATCH --account=proj42\n", "#SBATCH --qos=long\n", "#SBATCH --time=4:00:00\n",
                           "#SBATCH --mem=8G\n", "#SBATCH --cpus-per-task=16\n", "#SBATCH --gres=gpu:1\n",
                           "#SBATCH --exclusive\n"})
    EXPECT_NE(array.find(line), std::string::npos) << line << array;
  for (const char* line : {"#SBATCH --account=proj42\n", "#SBATCH --qos=long\n", "#SBATCH --time=0:30:00\n",
                           "#SBATCH --mem=1G\n", "#SBATCH --mail-type=END\n"})
    EXPECT_NE(merge.find(line), std::string::npos) << line << merge;
  for (const char* task_only : {"--time=4:00:00", "--mem=8G", "--cpus-per-task", "--gres", "--exclusive"})
    EXPECT_EQ(merge.find(task_only), std::string::npos) << task_only << merge;
  EXPECT_EQ(array.find("--mail-type"), std::string::npos) << array;

  // The merge job's defaults are small, not the tasks'.
  const auto d = test::run_cellbake("submit " + (dir / "bake.toml").string() + " --shards 2 --time 9:00:00 --dry-run");
  ASSERT_EQ(d.exit_code, 0) << d.output;
  EXPECT_NE(d.output.find("#SBATCH --time=01:00:00\n#SBATCH --mem=2G\nset -euo pipefail\nexec"), std::string::npos)
      << d.output;

  // An option the scripts set themselves, or a word that is no option, is refused before anything is written.
  const auto bad = test::run_cellbake("submit " + (dir / "bake.toml").string() +
                                      " --shards 2 --sbatch-arg=--array=0-99 --dry-run");
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_NE(bad.output.find("--array"), std::string::npos) << bad.output;
  const auto word = test::run_cellbake("submit " + (dir / "bake.toml").string() +
                                       " --shards 2 --merge-sbatch-arg=exclusive --dry-run");
  EXPECT_EQ(word.exit_code, 1) << word.output;
  EXPECT_NE(submit_help().find("--merge-mem TEXT=2G"), std::string::npos) << submit_help();
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

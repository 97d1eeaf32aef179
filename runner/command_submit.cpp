// `cellbake submit CONFIG --shards N [--partition P] [--account A] [--qos Q]
// [--time T] [--mem M] [--cpus-per-task C] [--sbatch-arg OPT]... [--merge-time T]
// [--merge-mem M] [--merge-sbatch-arg OPT]... [--set k=v]... [--floors all|0,2] [--out MERGED.db]
// [--out-dir DIR] [--dry-run]`: a distributed bake on Slurm — a job array of
// shard bakes plus a merge job that runs after every task succeeded (see
// runner/slurm_scripts.h).
#include <CLI/CLI.hpp>

#include <array>
#include <cstdio>
#include <sys/wait.h>

#include "runner/bake_command_options.h"
#include "runner/commands.h"
#include "runner/slurm_scripts.h"
#include "storage/output_file.h"

namespace cellbake {
namespace {

struct SubmitOptions {
  std::string config_file, out, out_dir, partition, account, qos, time, mem, floors;
  SlurmBakeJob defaults;  // the merge job's limits
  std::vector<std::string> sets, sbatch_args, merge_sbatch_args;
  int shards = 0, cpus_per_task = 0;
  bool dry_run = false;
};

// True for an override of output.database (the shard tasks get their own --out).
bool sets_output_database(const std::string& assignment) {
  std::string key = assignment.substr(0, assignment.find('='));
  key.erase(0, key.find_first_not_of(" \t"));
  key.erase(key.find_last_not_of(" \t") + 1);
  return key == "output.database";
}

std::string absolute_text(const std::filesystem::path& p) {
  return std::filesystem::absolute(p).lexically_normal().string();
}

// Runs `sbatch --parsable ARGS SCRIPT` and returns the job id it prints.
std::string sbatch(const std::string& args, const std::string& script) {
  const std::string cmd = "sbatch --parsable " + args + " " + shell_quote(script) + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot run sbatch");
  std::string output;
  std::array<char, 4096> buf{};
  for (std::size_t n; (n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0;) output.append(buf.data(), n);
  const int status = pclose(pipe);
  const std::string id = output.substr(0, output.find_first_of(";\n"));
  const bool numeric = !id.empty() && id.find_first_not_of("0123456789") == std::string::npos;
  if (status != 0 || !numeric)
    throw std::runtime_error("`" + cmd.substr(0, cmd.size() - 5) + "` failed" +
                             (WIFEXITED(status) && WEXITSTATUS(status) == 127 ? " (sbatch not found)" : "") + ": " +
                             output);
  return id;
}

}  // namespace

void add_submit_command(CLI::App& app) {
  auto opt = std::make_shared<SubmitOptions>();
  CLI::App* cmd = app.add_subcommand(
      "submit", "Bake on a Slurm cluster: a job array of N shard bakes, then a merge job into one database");
  cmd->add_option("config", opt->config_file, "Bake configuration (TOML)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--shards", opt->shards, "Number of shards = array tasks")->required()->check(CLI::Range(1, 100000));
  cmd->add_option("--set", opt->sets, "Override a config key: section.key=value (repeatable; passed to every task)");
  cmd->add_option("--floors", opt->floors,
                  "Bake whole floors: all, or indices like 0,2 of those `cellbake info` finds (passed to every task; "
                  "see bake --help)");
  cmd->add_option("--out", opt->out, "Merged cell database (default: the config's [output] database)");
  cmd->add_option("--out-dir", opt->out_dir, "Folder for shard databases, scripts and logs (default: MERGED_shards)");
  cmd->add_option("--partition", opt->partition, "Slurm partition of both jobs (sbatch --partition)");
  cmd->add_option("--account", opt->account, "Account charged for both jobs (sbatch --account)");
  cmd->add_option("--qos", opt->qos, "Quality of service of both jobs (sbatch --qos)");
  cmd->add_option("--time", opt->time, "Time limit per bake task (sbatch --time; default: the partition's)");
  cmd->add_option("--mem", opt->mem, "Memory per bake task (sbatch --mem; default: the partition's)");
  cmd->add_option("--cpus-per-task", opt->cpus_per_task,
                  "Cores per bake task (sbatch --cpus-per-task); each task bakes with that many threads "
                  "(default: the cluster's allocation, and as many threads as CPUs the task may use)")
      ->check(CLI::Range(1, 1024));
  cmd->add_option("--sbatch-arg", opt->sbatch_args,
                  "One more sbatch option for the bake tasks, as one word: --sbatch-arg=--gres=gpu:1 (repeatable)")
      ->allow_extra_args(false);
  cmd->add_option("--merge-time", opt->defaults.merge_time, "Time limit of the merge job (sbatch --time)")
      ->capture_default_str();
  cmd->add_option("--merge-mem", opt->defaults.merge_mem, "Memory of the merge job (sbatch --mem)")->capture_default_str();
  cmd->add_option("--merge-sbatch-arg", opt->merge_sbatch_args,
                  "One more sbatch option for the merge job, as one word (repeatable)")
      ->allow_extra_args(false);
  cmd->add_flag("--dry-run", opt->dry_run, "Print both scripts and submit nothing");
  cmd->callback([opt] {
    // Validate the configuration and options here, before anything reaches the cluster.
    for (const auto& a : opt->sbatch_args) check_sbatch_arg(a, "--sbatch-arg");
    for (const auto& a : opt->merge_sbatch_args) check_sbatch_arg(a, "--merge-sbatch-arg");
    BakeCommandOptions bake;
    bake.config_file = opt->config_file;
    bake.sets = opt->sets;
    bake.out = opt->out;
    bake.floors = opt->floors;
    const BakeConfig config = bake_config_from_options(bake);

    SlurmBakeJob job;
    job.binary = absolute_text(std::filesystem::read_symlink("/proc/self/exe"));
    job.bake_args.push_back(absolute_text(opt->config_file));
    for (const auto& s : opt->sets)
      if (!sets_output_database(s)) job.bake_args.insert(job.bake_args.end(), {"--set", s});
    if (!opt->floors.empty()) job.bake_args.insert(job.bake_args.end(), {"--floors", opt->floors});
    job.shards = opt->shards;
    job.merged_db = absolute_text(config.database);
    const std::filesystem::path merged(job.merged_db);
    job.out_dir = absolute_text(opt->out_dir.empty() ? merged.parent_path() / (merged.stem().string() + "_shards")
                                                     : std::filesystem::path(opt->out_dir));
    job.workdir = absolute_text(std::filesystem::current_path());
    job.partition = opt->partition;
    job.account = opt->account;
    job.qos = opt->qos;
    job.time = opt->time;
    job.mem = opt->mem;
    job.cpus_per_task = opt->cpus_per_task;
    job.sbatch_args = opt->sbatch_args;
    job.merge_time = opt->defaults.merge_time;
    job.merge_mem = opt->defaults.merge_mem;
    job.merge_sbatch_args = opt->merge_sbatch_args;

    const std::string array_file = job.out_dir + "/bake_array.sbatch", merge_file = job.out_dir + "/merge.sbatch";
    if (opt->dry_run) {
      std::printf("# %s\n%s\n# %s\n%s\n", array_file.c_str(), array_script(job).c_str(), merge_file.c_str(),
                  merge_script(job).c_str());
      std::printf("# dry run: would run `sbatch --parsable %s`, then `sbatch --parsable "
                  "--dependency=afterok:ARRAY_JOB_ID %s`; nothing submitted\n",
                  array_file.c_str(), merge_file.c_str());
      return;
    }
    std::filesystem::create_directories(job.out_dir + "/logs");
    std::filesystem::create_directories(merged.parent_path());
    write_output_file(array_file, array_script(job), {opt->config_file});
    write_output_file(merge_file, merge_script(job), {opt->config_file});
    const std::string array_id = sbatch("", array_file);
    std::string merge_id;
    try {
      merge_id = sbatch("--dependency=afterok:" + array_id, merge_file);
    } catch (const std::exception& e) {
      throw std::runtime_error("array job " + array_id + " was submitted but the merge job was not (" + e.what() +
                               "); submit it with: sbatch --dependency=afterok:" + array_id + " " + merge_file);
    }
    std::printf("array job %s: %d shard bakes -> %s/shard_<K>.db (logs in %s/logs)\n", array_id.c_str(), job.shards,
                job.out_dir.c_str(), job.out_dir.c_str());
    std::printf("merge job %s: after array job %s succeeds -> %s\n", merge_id.c_str(), array_id.c_str(),
                job.merged_db.c_str());
    std::printf("watch: squeue -j %s,%s; cellbake status %s/shard_*.db\n", array_id.c_str(), merge_id.c_str(),
                job.out_dir.c_str());
    std::printf("rerun a failed task K: sbatch --array=K %s, then: sbatch %s\n", array_file.c_str(), merge_file.c_str());
  });
}

}  // namespace cellbake

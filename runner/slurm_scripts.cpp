#include "runner/slurm_scripts.h"

#include <sstream>
#include <stdexcept>

namespace cellbake {
namespace {

struct Limits {
  const std::string& time;
  const std::string& mem;
  int cpus_per_task;
  const std::vector<std::string>& extra;
};

// The #SBATCH header of one script.
std::string header(const SlurmBakeJob& job, const std::string& name, const std::string& log, const Limits& limits) {
  std::ostringstream o;
  o << "#!/bin/bash\n";
  o << "#SBATCH --job-name=" << name << "\n";
  o << "#SBATCH --output=" << job.out_dir << "/logs/" << log << "\n";
  o << "#SBATCH --chdir=" << job.workdir << "\n";
  if (!job.partition.empty()) o << "#SBATCH --partition=" << job.partition << "\n";
  if (!job.account.empty()) o << "#SBATCH --account=" << job.account << "\n";
  if (!job.qos.empty()) o << "#SBATCH --qos=" << job.qos << "\n";
  if (!limits.time.empty()) o << "#SBATCH --time=" << limits.time << "\n";
  if (!limits.mem.empty()) o << "#SBATCH --mem=" << limits.mem << "\n";
  if (limits.cpus_per_task > 0) o << "#SBATCH --cpus-per-task=" << limits.cpus_per_task << "\n";
  for (const auto& a : limits.extra) o << "#SBATCH " << a << "\n";
  return o.str();
}

std::string command_line(const SlurmBakeJob& job, const std::string& subcommand) {
  return "exec " + shell_quote(job.binary) + " " + subcommand;
}

}  // namespace

void check_sbatch_arg(const std::string& arg, const std::string& what) {
  if (arg.empty() || arg[0] != '-')
    throw std::invalid_argument(what + " '" + arg + "': expected an sbatch option such as --gres=gpu:1");
  if (arg.find_first_of(std::string("\n\r\0", 3)) != std::string::npos)
    throw std::invalid_argument(what + ": an sbatch option cannot hold a line break");
  std::string name = arg.substr(0, arg.find_first_of("= \t"));
  for (const char* own : {"--array", "-a", "--output", "-o", "--chdir", "-D", "--job-name", "-J", "--parsable",
                          "--dependency", "-d", "--wrap"})
    if (name == own)
      throw std::invalid_argument(what + " '" + arg + "': cellbake submit sets " + name + " itself");
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string shard_db_path(const SlurmBakeJob& job, int index) {
  return job.out_dir + "/shard_" + std::to_string(index) + ".db";
}

std::string array_script(const SlurmBakeJob& job) {
  const std::string n = std::to_string(job.shards);
  std::ostringstream o;
  o << header(job, "cellbake-bake", "shard_%a.out", {job.time, job.mem, job.cpus_per_task, job.sbatch_args});
  o << "#SBATCH --array=0-" << job.shards - 1 << "\n";
  o << "# Task K bakes shard K of " << n << "; rerun one task alone with: sbatch --array=K THIS_SCRIPT\n";
  o << "set -euo pipefail\n";
  o << command_line(job, "bake");
  for (const auto& a : job.bake_args) o << " " << shell_quote(a);
  o << " --shard \"$SLURM_ARRAY_TASK_ID/" << n << "\"";
  o << " --out " << shell_quote(job.out_dir + "/shard_") << "\"$SLURM_ARRAY_TASK_ID\"'.db'";
  o << " --threads \"${SLURM_CPUS_PER_TASK:-$(nproc)}\"\n";
  return o.str();
}

std::string merge_script(const SlurmBakeJob& job) {
  std::ostringstream o;
  o << header(job, "cellbake-merge", "merge.out", {job.merge_time, job.merge_mem, 0, job.merge_sbatch_args});
  o << "set -euo pipefail\n";
  o << command_line(job, "merge") << " " << shell_quote(job.merged_db);
  for (int i = 0; i < job.shards; ++i) o << " \\\n  " << shell_quote(shard_db_path(job, i));
  o << "\n";
  return o.str();
}

}  // namespace cellbake

#include "runner/slurm_scripts.h"

#include <sstream>

namespace cellbake {
namespace {

// The #SBATCH header lines shared by both scripts.
std::string header(const SlurmBakeJob& job, const std::string& name, const std::string& log) {
  std::ostringstream o;
  o << "#!/bin/bash\n";
  o << "#SBATCH --job-name=" << name << "\n";
  o << "#SBATCH --output=" << job.out_dir << "/logs/" << log << "\n";
  o << "#SBATCH --chdir=" << job.workdir << "\n";
  if (!job.partition.empty()) o << "#SBATCH --partition=" << job.partition << "\n";
  if (!job.time.empty()) o << "#SBATCH --time=" << job.time << "\n";
  if (!job.mem.empty()) o << "#SBATCH --mem=" << job.mem << "\n";
  return o.str();
}

std::string command_line(const SlurmBakeJob& job, const std::string& subcommand) {
  return "exec " + shell_quote(job.binary) + " " + subcommand;
}

}  // namespace

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
  o << header(job, "cellbake-bake", "shard_%a.out");
  o << "#SBATCH --array=0-" << job.shards - 1 << "\n";
  o << "# Task K bakes shard K of " << n << "; rerun one task alone with: sbatch --array=K THIS_SCRIPT\n";
  o << "set -euo pipefail\n";
  o << command_line(job, "bake");
  for (const auto& a : job.bake_args) o << " " << shell_quote(a);
  o << " --shard \"$SLURM_ARRAY_TASK_ID/" << n << "\"";
  o << " --out " << shell_quote(job.out_dir + "/shard_") << "\"$SLURM_ARRAY_TASK_ID\"'.db'";
  o << " --threads \"${SLURM_CPUS_PER_TASK:-1}\" --quiet\n";
  return o.str();
}

std::string merge_script(const SlurmBakeJob& job) {
  std::ostringstream o;
  o << header(job, "cellbake-merge", "merge.out");
  o << "set -euo pipefail\n";
  o << command_line(job, "merge") << " " << shell_quote(job.merged_db);
  for (int i = 0; i < job.shards; ++i) o << " \\\n  " << shell_quote(shard_db_path(job, i));
  o << "\n";
  return o.str();
}

}  // namespace cellbake

// The batch scripts of a distributed bake on Slurm: a job array whose task K
// bakes shard K of N into its own database, and a merge job that combines
// them. Pure text generation (no Slurm calls), so it is testable anywhere.
#pragma once

#include <string>
#include <vector>

namespace cellbake {

struct SlurmBakeJob {
  std::string binary;                 // absolute path of the cellbake executable
  std::vector<std::string> bake_args; // config and option arguments for `cellbake bake`, unquoted (absolute paths)
  int shards = 1;                     // array tasks 0..shards-1
  std::string out_dir;                // absolute: shard databases, scripts and logs go here
  std::string merged_db;              // absolute path of the merged database
  std::string workdir;                // absolute: the jobs' working directory
  // Both jobs (empty = cluster default): where they run and who pays.
  std::string partition, account, qos;
  // The bake tasks (empty / 0 = cluster default).
  std::string time, mem;              // sbatch --time, --mem per task
  int cpus_per_task = 0;              // sbatch --cpus-per-task; each task bakes with that many threads
  std::vector<std::string> sbatch_args;  // more #SBATCH options for the tasks, verbatim ("--gres=gpu:1")
  // The merge job: one core, its own limits (small by default: merging copies rows).
  std::string merge_time = "01:00:00", merge_mem = "2G";
  std::vector<std::string> merge_sbatch_args;  // more #SBATCH options for the merge job
};

// Throws std::invalid_argument when an extra sbatch option cannot go on an
// `#SBATCH` line as given: empty, not starting with '-', holding a line break
// or NUL, or one the scripts set themselves (--array, --output, --chdir,
// --job-name, --parsable, --dependency, --wrap). `what` names the option in
// the message ("--sbatch-arg").
void check_sbatch_arg(const std::string& arg, const std::string& what);

// Quotes `text` for a POSIX shell (single quotes; safe for any bytes but NUL).
std::string shell_quote(const std::string& text);

// The shard database of array task `index` ("OUT_DIR/shard_<index>.db").
std::string shard_db_path(const SlurmBakeJob& job, int index);

// The array script: `#SBATCH --array=0-(N-1)` and the task options; task
// $SLURM_ARRAY_TASK_ID runs `cellbake bake ARGS --shard $SLURM_ARRAY_TASK_ID/N
// --out OUT_DIR/shard_$SLURM_ARRAY_TASK_ID.db --threads T` with T =
// $SLURM_CPUS_PER_TASK, else the CPUs the task may use (`nproc`). Progress
// lines go to the task's log (OUT_DIR/logs/shard_<K>.out). `sbatch --array=K`
// on the same script reruns task K alone (it resumes from its shard database).
std::string array_script(const SlurmBakeJob& job);

// The merge script: `cellbake merge MERGED_DB shard_0.db ... shard_(N-1).db`
// with the merge job's own time and memory.
std::string merge_script(const SlurmBakeJob& job);

}  // namespace cellbake

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
  std::string partition, time, mem;   // sbatch options; empty = cluster default
};

// Quotes `text` for a POSIX shell (single quotes; safe for any bytes but NUL).
std::string shell_quote(const std::string& text);

// The shard database of array task `index` ("OUT_DIR/shard_<index>.db").
std::string shard_db_path(const SlurmBakeJob& job, int index);

// The array script: `#SBATCH --array=0-(N-1)`; task $SLURM_ARRAY_TASK_ID runs
// `cellbake bake ARGS --shard $SLURM_ARRAY_TASK_ID/N --out OUT_DIR/shard_$SLURM_ARRAY_TASK_ID.db
// --threads ${SLURM_CPUS_PER_TASK:-1} --quiet`. `sbatch --array=K` on the same
// script reruns task K alone (it resumes from its shard database).
std::string array_script(const SlurmBakeJob& job);

// The merge script: `cellbake merge MERGED_DB shard_0.db ... shard_(N-1).db`.
std::string merge_script(const SlurmBakeJob& job);

}  // namespace cellbake

// The distributed bake on a real single-node Slurm cluster (scripts/slurm-local.sh):
// `cellbake submit` with 4 shards, every array task and the merge job
// complete, the merged database has the content of a single-machine bake, and
// a rerun of one array task resumes from its shard. Skipped when the Slurm
// and munge daemons are not installed or the test is not root.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <regex>
#include <thread>

#include "fixture_room_obj.h"
#include "test_support.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

test::CommandResult shell(const std::string& command) { return test::run_shell(command); }

std::string missing_slurm_programs() {
  std::string missing;
  for (const char* p : {"sbatch", "squeue", "scontrol", "slurmctld", "slurmd", "munged"})
    if (shell(std::string("command -v ") + p).exit_code != 0) missing += std::string(" ") + p;
  return missing;
}

const std::filesystem::path kScript =
    std::filesystem::path(CELLBAKE_SOURCE_DIR) / "scripts" / "slurm-local.sh";

// A private single-node cluster for the test's lifetime: started in `dir`,
// always stopped (daemons ended by their pid files) when the guard goes.
class LocalSlurm {
 public:
  explicit LocalSlurm(const std::filesystem::path& dir) : env_("CELLBAKE_SLURM_DIR=" + dir.string() +
                                                               " CELLBAKE_SLURM_PORT=" +
                                                               std::to_string(17000 + 2 * (getpid() % 2000))) {
    setenv("SLURM_CONF", (dir / "slurm.conf").c_str(), 1);
    start_ = shell(env_ + " bash " + kScript.string() + " start");
  }
  ~LocalSlurm() {
    const auto r = shell(env_ + " bash " + kScript.string() + " stop");
    if (r.exit_code != 0) ADD_FAILURE() << "slurm-local.sh stop: " << r.output;
    unsetenv("SLURM_CONF");
  }
  LocalSlurm(const LocalSlurm&) = delete;
  LocalSlurm& operator=(const LocalSlurm&) = delete;
  const test::CommandResult& start_result() const { return start_; }

 private:
  std::string env_;
  test::CommandResult start_;
};

// Waits until squeue no longer lists `job` (pending or running); false on timeout.
bool wait_for_job(const std::string& job, double timeout_s) {
  const auto t0 = Clock::now();
  while (seconds_since(t0) < timeout_s) {
    if (shell("squeue -h -j " + job).output.find_first_not_of(" \n") == std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  return false;
}

// `scontrol -o show job` lines (one per array task) that are not COMPLETED with exit code 0:0,
// or a message when there are not `expected` lines.
std::string unfinished_tasks(const std::string& job, std::size_t expected) {
  const auto r = shell("scontrol -o show job " + job);
  std::string bad;
  std::size_t lines = 0;
  std::istringstream in(r.output);
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    ++lines;
    if (line.find("JobState=COMPLETED") == std::string::npos || line.find(" ExitCode=0:0") == std::string::npos)
      bad += line + "\n";
  }
  if (lines != expected) bad += "expected " + std::to_string(expected) + " task(s), got: " + r.output;
  return bad;
}

std::string status_hash(const std::string& databases) {
  const auto r = test::run_cellbake("status " + databases + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"cells_done\": 16"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"cells_pending\": 0"), std::string::npos) << r.output;
  const auto at = r.output.find("\"content_hash\": \"");
  return at == std::string::npos ? "(no content hash) " + r.output : r.output.substr(at + 17, 32);
}

std::string logs_of(const std::filesystem::path& dir) {
  std::string all;
  if (!std::filesystem::exists(dir)) return all;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    std::ifstream in(e.path());
    all += "== " + e.path().string() + "\n" + std::string(std::istreambuf_iterator<char>(in), {});
  }
  return all;
}

TEST(Slurm, SubmittedShardBakeMergesToTheSingleMachineResult) {
  if (const std::string missing = missing_slurm_programs(); !missing.empty())
    GTEST_SKIP() << "Slurm is not installed (missing:" << missing
                 << "); scripts/install-deps.sh installs slurmctld slurmd slurm-client munge";
  if (geteuid() != 0) GTEST_SKIP() << "scripts/slurm-local.sh runs the Slurm daemons as root; not root";

  test::TempDir dir;
  const auto t_start = Clock::now();
  LocalSlurm cluster(dir / "slurm");
  ASSERT_EQ(cluster.start_result().exit_code, 0) << cluster.start_result().output << logs_of(dir / "slurm" / "log");
  const double start_s = seconds_since(t_start);

  test::write_text(dir / "room.obj", test::room_obj());
  const auto ingest = test::run_cellbake("ingest " + (dir / "room.obj").string() + " --store " +
                                         (dir / "room.store.db").string() + " --chunk-triangles 128");
  ASSERT_EQ(ingest.exit_code, 0) << ingest.output;
  test::write_text(dir / "bake.toml",
                   "[model]\nstore = \"room.store.db\"\n"
                   "[[regions]]\nmin = [1.0, 1.0, 1.6]\nmax = [9.0, 9.0, 1.6]\n"  // 4 x 4 cells of 2 m
                   "[cells]\nsize = 2.0\n[near]\nbudget = 600\n[sample]\nface_size = 32\n"
                   "[encode]\nimage_format = \"png\"\n[output]\ndatabase = \"merged.db\"\n");

  const auto t_submit = Clock::now();
  const auto submit = test::run_cellbake("submit " + (dir / "bake.toml").string() + " --shards 4 --time 5 --out-dir " +
                                         (dir / "shards").string());
  ASSERT_EQ(submit.exit_code, 0) << submit.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(submit.output, m, std::regex("array job (\\d+)"))) << submit.output;
  const std::string array_job = m[1];
  ASSERT_TRUE(std::regex_search(submit.output, m, std::regex("merge job (\\d+)"))) << submit.output;
  const std::string merge_job = m[1];

  ASSERT_TRUE(wait_for_job(array_job, 90)) << "array job " << array_job << " still queued after 90 s\n"
                                            << shell("squeue -t all").output << logs_of(dir / "shards" / "logs");
  const double array_s = seconds_since(t_submit);
  EXPECT_EQ(unfinished_tasks(array_job, 4), "") << logs_of(dir / "shards" / "logs");
  ASSERT_TRUE(wait_for_job(merge_job, 30)) << "merge job " << merge_job << " still queued\n"
                                            << shell("scontrol -o show job " + merge_job).output;
  const double merge_s = seconds_since(t_submit);
  EXPECT_EQ(unfinished_tasks(merge_job, 1), "") << logs_of(dir / "shards" / "logs");
  ASSERT_TRUE(std::filesystem::exists(dir / "merged.db")) << logs_of(dir / "shards" / "logs");
  {
    // Task logs hold the bake's progress lines (tasks do not run --quiet).
    std::ifstream log0(dir / "shards" / "logs" / "shard_0.out");
    const std::string text(std::istreambuf_iterator<char>(log0), {});
    EXPECT_TRUE(std::regex_search(text, std::regex("bake: \\d+/\\d+ cells \\("))) << text;
  }

  // The same config baked on this machine in one process.
  const auto t_local = Clock::now();
  const auto local = test::run_cellbake("bake " + (dir / "bake.toml").string() + " --out " +
                                        (dir / "single.db").string() + " --threads 2 --quiet");
  ASSERT_EQ(local.exit_code, 0) << local.output;
  const double local_s = seconds_since(t_local);

  const std::string single = status_hash((dir / "single.db").string());
  EXPECT_EQ(status_hash((dir / "merged.db").string()), single);
  std::string shards;
  for (int i = 0; i < 4; ++i) shards += (dir / "shards" / ("shard_" + std::to_string(i) + ".db")).string() + " ";
  EXPECT_EQ(status_hash(shards), single);

  // Rerunning one array task alone resumes from its shard database: nothing to redo.
  const auto rerun = shell("sbatch --parsable --array=1 " + (dir / "shards" / "bake_array.sbatch").string());
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  const std::string rerun_job = rerun.output.substr(0, rerun.output.find_first_of(";\n"));
  ASSERT_TRUE(wait_for_job(rerun_job, 30));
  EXPECT_EQ(unfinished_tasks(rerun_job, 1), "");
  std::ifstream log(dir / "shards" / "logs" / "shard_1.out");
  const std::string rerun_log(std::istreambuf_iterator<char>(log), {});
  EXPECT_TRUE(std::regex_search(rerun_log, std::regex("(\\d+) cells selected, \\1 up to date, 0 baked"))) << rerun_log;

  std::printf("[ timing ] cluster start %.2f s; submit -> array done %.2f s; -> merge done %.2f s; "
              "local single bake %.2f s; total %.2f s\n",
              start_s, array_s, merge_s, local_s, seconds_since(t_start));
}

}  // namespace
}  // namespace cellbake

// Randomized kill -9 test (issue #14): a small bake and a merge are killed at
// seeded random points; after every kill the database passes SQLite's
// integrity check, and rerunning the same command ends with the reference
// content hash and a clean `status --check`.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <random>
#include <sstream>
#include <thread>

#include "pipeline/ingest.h"
#include "storage/cell_db.h"
#include "tests/fixture_room_obj.h"
#include "tests/fixture_box_store.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

// Runs `args` with the cellbake binary and kills it with SIGKILL after
// `delay` (if it is still running). Returns true when it was killed.
bool run_and_kill(const std::string& args, std::chrono::microseconds delay) {
  const std::string cmd = "exec " + std::string(CELLBAKE_BINARY) + " " + args + " >/dev/null 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  std::this_thread::sleep_for(delay);
  int status = 0;
  const bool killed = waitpid(pid, &status, WNOHANG) == 0;
  if (killed) {
    kill(pid, SIGKILL);
    waitpid(pid, &status, 0);
  }
  return killed;
}

double seconds_of(const std::string& args) {
  const auto t0 = Clock::now();
  const auto r = test::run_cellbake(args);
  EXPECT_EQ(r.exit_code, 0) << args << ": " << r.output;
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

class KillResume : public ::testing::Test {
 protected:
  void SetUp() override { test::ingest_box_with_pillar(dir_.path()); }
  // The bake of 3 x 3 cells into `out` (extra: e.g. a shard).
  std::string bake_args(const std::string& out, const std::string& extra = "") const {
    return "bake --store " + (dir_ / "s.db").string() + " --region=0.5,0.5,1,3.5,3.5,1 --cell-size 1 " +
           "--face-size 16 --quiet --threads 2 --out " + (dir_ / out).string() + " " + extra;
  }
  std::string content_hash(const std::string& db) const {
    return CellDb(dir_ / db, CellDb::Mode::read_only).totals().content_hash;
  }
  // SQLite's integrity check of a database a killed command left (absent is fine: killed before creating it).
  void expect_intact(const std::string& db, int round) const {
    if (!std::filesystem::exists(dir_ / db)) return;
    try {
      EXPECT_TRUE(CellDb(dir_ / db, CellDb::Mode::read_only).integrity_ok()) << "round " << round;
    } catch (const std::exception& e) {
      // Killed between creating the file and committing its schema: nothing to check yet.
      EXPECT_NE(std::string(e.what()).find("schema version"), std::string::npos) << "round " << round << ": " << e.what();
    }
  }
  test::TempDir dir_;
};

TEST_F(KillResume, TenKilledBakesAndTenKilledMergesAllResumeToTheReferenceHash) {
  std::mt19937 random(14);  // fixed seed: the same kill points every run
  const double bake_seconds = seconds_of(bake_args("ref.db"));
  const std::string reference = content_hash("ref.db");
  ASSERT_EQ(CellDb(dir_ / "ref.db", CellDb::Mode::read_only).totals().cells_done, 9u);

  int killed = 0;
  for (int round = 0; round < 10; ++round) {
    const std::string db = "bake" + std::to_string(round) + ".db";
    std::uniform_real_distribution<double> at(0.0, bake_seconds);
    killed += run_and_kill(bake_args(db), std::chrono::microseconds(std::int64_t(at(random) * 1e6)));
    expect_intact(db, round);
    const auto resumed = test::run_cellbake(bake_args(db));
    ASSERT_EQ(resumed.exit_code, 0) << "round " << round << ": " << resumed.output;
    EXPECT_EQ(content_hash(db), reference) << "round " << round;
    EXPECT_TRUE(CellDb(dir_ / db, CellDb::Mode::read_only).integrity_ok()) << "round " << round;
  }
  EXPECT_GE(killed, 5) << "most kills should land while the bake runs";

  ASSERT_EQ(test::run_cellbake(bake_args("shard0.db", "--shard 0/2")).exit_code, 0);
  ASSERT_EQ(test::run_cellbake(bake_args("shard1.db", "--shard 1/2")).exit_code, 0);
  const auto merge_args = [&](const std::string& out) {
    return "merge " + (dir_ / out).string() + " " + (dir_ / "shard0.db").string() + " " + (dir_ / "shard1.db").string();
  };
  const double merge_seconds = seconds_of(merge_args("merge_ref.db"));
  ASSERT_EQ(content_hash("merge_ref.db"), reference);
  for (int round = 0; round < 10; ++round) {
    const std::string db = "merge" + std::to_string(round) + ".db";
    std::uniform_real_distribution<double> at(0.0, merge_seconds);
    run_and_kill(merge_args(db), std::chrono::microseconds(std::int64_t(at(random) * 1e6)));
    expect_intact(db, round);
    const auto resumed = test::run_cellbake(merge_args(db));
    ASSERT_EQ(resumed.exit_code, 0) << "round " << round << ": " << resumed.output;
    EXPECT_EQ(content_hash(db), reference) << "round " << round;
    const auto check = test::run_cellbake("status --check " + (dir_ / db).string());
    EXPECT_EQ(check.exit_code, 0) << "round " << round << ": " << check.output;
  }
}

}  // namespace
}  // namespace cellbake

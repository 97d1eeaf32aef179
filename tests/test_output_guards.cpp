// Output paths are guarded (issue #14, items 1-3): a bake never adopts a
// geometry store or another file as its cell database, an ingest never
// replaces a cell database, a device, a directory, a pipe or a symbolic link,
// and temporaries of killed ingests are cleaned up. Issue #41, item 6: the
// bake lock follows the database file, not the name it is reached by.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <sstream>

#include "pipeline/ingest.h"
#include "storage/cell_db.h"
#include "storage/cell_db_lock.h"
#include "storage/geometry_store.h"
#include "tests/fixture_room_obj.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

ParallelFor serial() {
  return [](std::size_t n, const std::function<void(std::size_t)>& fn) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
  };
}

// A small model ingested into dir/s.db; returns the OBJ path.
std::filesystem::path make_store(const test::TempDir& dir) {
  std::ostringstream o;
  int next = 1;
  test::obj_box(o, next, {0, 0, 0}, {4, 4, 3}, 2);
  test::write_text(dir / "box.obj", o.str());
  ingest_models({dir / "box.obj"}, dir / "s.db", IngestParams{}, serial());
  return dir / "box.obj";
}

std::string bake_into(const test::TempDir& dir, const std::filesystem::path& out) {
  return "bake --store " + (dir / "s.db").string() + " --region=1,1,1,3,3,2 --cell-size 2 --face-size 16 --quiet --out " +
         out.string();
}

TEST(OutputGuards, BakeRefusesToTurnAGeometryStoreIntoACellDatabase) {
  test::TempDir dir;
  make_store(dir);
  const std::uint64_t bytes = std::filesystem::file_size(dir / "s.db");
  for (const auto& out : {dir / "s.db"}) {
    const auto r = test::run_cellbake(bake_into(dir, out));
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("is not a cellbake cell database"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("cellbake-geometry-store"), std::string::npos) << r.output;
  }
  // The store is untouched and still a store.
  EXPECT_EQ(std::filesystem::file_size(dir / "s.db"), bytes);
  GeometryStore store(dir / "s.db");
  EXPECT_GT(store.summary().triangles, 0u);
  // Any other SQLite file with tables is refused too; an empty file is a new database.
  test::write_text(dir / "empty.db", "");
  EXPECT_EQ(test::run_cellbake(bake_into(dir, dir / "empty.db")).exit_code, 0);
  CellDb baked(dir / "empty.db", CellDb::Mode::read_only);
  EXPECT_FALSE(baked.cell_ids().empty());
}

TEST(OutputGuards, BakeRefusesDirectoriesAndPipes) {
  test::TempDir dir;
  make_store(dir);
  std::filesystem::create_directory(dir / "folder.db");
  ASSERT_EQ(::mkfifo((dir / "pipe.db").c_str(), 0600), 0);
  for (const auto& out : {dir / "folder.db", dir / "pipe.db"}) {
    const auto r = test::run_cellbake(bake_into(dir, out));
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("not a regular file"), std::string::npos) << r.output;
  }
  EXPECT_TRUE(std::filesystem::is_fifo(dir / "pipe.db"));
}

TEST(OutputGuards, IngestNeverReplacesACellDatabaseADeviceADirectoryAPipeOrALink) {
  test::TempDir dir;
  const auto obj = make_store(dir);
  ASSERT_EQ(test::run_cellbake(bake_into(dir, dir / "cells.db")).exit_code, 0);
  const std::uint64_t cells_bytes = std::filesystem::file_size(dir / "cells.db");
  std::filesystem::create_directory(dir / "folder.db");
  ASSERT_EQ(::mkfifo((dir / "pipe.db").c_str(), 0600), 0);
  std::filesystem::create_symlink(dir / "s.db", dir / "link.db");
  struct Case {
    std::filesystem::path target;
    const char* message;
  };
  for (const Case& c : {Case{dir / "cells.db", "is not a cellbake geometry store"},
                        Case{"/dev/null", "not a regular file"}, Case{dir / "folder.db", "not a regular file"},
                        Case{dir / "pipe.db", "not a regular file"}, Case{dir / "link.db", "symbolic link"}}) {
    const auto r = test::run_cellbake("ingest " + obj.string() + " --store " + c.target.string());
    EXPECT_NE(r.exit_code, 0) << c.target << ": " << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.target << ": " << r.output;
  }
  EXPECT_EQ(std::filesystem::file_size(dir / "cells.db"), cells_bytes);
  CellDb cells(dir / "cells.db", CellDb::Mode::read_only);
  EXPECT_FALSE(cells.cell_ids().empty());
  EXPECT_TRUE(std::filesystem::is_character_file("/dev/null"));
  EXPECT_TRUE(std::filesystem::is_directory(dir / "folder.db"));
  EXPECT_TRUE(std::filesystem::is_fifo(dir / "pipe.db"));
  EXPECT_TRUE(std::filesystem::is_symlink(dir / "link.db"));
  // Replacing an existing geometry store (re-ingest) still works.
  EXPECT_EQ(test::run_cellbake("ingest " + obj.string() + " --store " + (dir / "s.db").string()).exit_code, 0);
}

// A pid that no longer runs: a child that exited and was reaped.
pid_t dead_pid() {
  const pid_t child = ::fork();
  if (child == 0) ::_exit(0);
  int status = 0;
  ::waitpid(child, &status, 0);
  return child;
}

TEST(OutputGuards, TemporariesOfKilledIngestsAreRemovedOnlyWhenStale) {
  test::TempDir dir;
  const auto obj = make_store(dir);
  const pid_t gone = dead_pid();
  const auto old_time = std::filesystem::file_time_type::clock::now() - std::chrono::hours(2);
  const auto temp = [&](const std::string& suffix, pid_t pid, bool old) {
    const auto path = dir / ("s.db" + suffix + std::to_string(pid));
    test::write_text(path, "half a store");
    if (old) std::filesystem::last_write_time(path, old_time);
    return path;
  };
  const auto stale_tmp = temp(".tmp-", gone, true);
  const auto stale_spill = temp(".spill-", gone, true);
  const auto recent = temp(".tmp-", dead_pid(), false);  // may be a live ingest on another machine
  const auto alive = temp(".tmp-", 1, true);  // pid 1 always runs
  const auto other = dir / ("other.db.tmp-" + std::to_string(gone));
  test::write_text(other, "another store's");
  std::filesystem::last_write_time(other, old_time);

  ingest_models({obj}, dir / "s.db", IngestParams{}, serial());
  EXPECT_FALSE(std::filesystem::exists(stale_tmp));
  EXPECT_FALSE(std::filesystem::exists(stale_spill));
  EXPECT_TRUE(std::filesystem::exists(recent));
  EXPECT_TRUE(std::filesystem::exists(alive));
  EXPECT_TRUE(std::filesystem::exists(other));
}

// A child process that holds the bake lock of `database` until it is killed.
pid_t hold_bake_lock(const std::filesystem::path& database) {
  int ready[2];
  if (::pipe(ready) != 0) return -1;
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(ready[0]);
    try {
      const CellDbLock held(database, "baked");
      if (::write(ready[1], "1", 1) != 1) ::_exit(1);
      ::pause();
    } catch (...) {
    }
    ::_exit(1);
  }
  ::close(ready[1]);
  char byte = 0;
  const bool locked = ::read(ready[0], &byte, 1) == 1;
  ::close(ready[0]);
  return locked ? child : -1;
}

TEST(OutputGuards, TheBakeLockFollowsTheDatabaseNotItsName) {
  test::TempDir dir;
  make_store(dir);
  ASSERT_EQ(test::run_cellbake(bake_into(dir, dir / "cells.db")).exit_code, 0);
  std::filesystem::create_symlink(dir / "cells.db", dir / "link.db");
  std::filesystem::create_hard_link(dir / "cells.db", dir / "hard.db");
  std::filesystem::create_directory_symlink(dir.path(), dir / "linked_folder");
  const pid_t holder = hold_bake_lock(dir / "cells.db");
  ASSERT_GT(holder, 0);
  for (const auto& name : {dir / "link.db", dir / "hard.db", dir / "linked_folder" / "cells.db"}) {
    const auto r = test::run_cellbake(bake_into(dir, name));
    EXPECT_NE(r.exit_code, 0) << name << ": " << r.output;
    EXPECT_NE(r.output.find("database " + name.string() + " is being baked by pid " + std::to_string(holder)),
              std::string::npos)
        << r.output;
    EXPECT_THROW(CellDbLock(name, "merged into"), std::runtime_error) << name;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "hard.db.lock"));  // a refused opener leaves no lock file
  ::kill(holder, SIGKILL);                                      // kill -9 releases both locks
  ::waitpid(holder, nullptr, 0);
  const auto after = test::run_cellbake(bake_into(dir, dir / "hard.db"));
  EXPECT_EQ(after.exit_code, 0) << after.output;
  {  // the other way round: held through the hard link, the original name is refused
    const CellDbLock held(dir / "hard.db", "merged into");
    const auto r = test::run_cellbake(bake_into(dir, dir / "cells.db"));
    EXPECT_NE(r.output.find("is being merged into by pid " + std::to_string(::getpid())), std::string::npos)
        << r.output;
  }
  {  // a database that does not exist yet: created to be locked, removed again while still empty
    const CellDbLock held(dir / "new.db", "baked");
    EXPECT_TRUE(std::filesystem::exists(dir / "new.db"));
    EXPECT_THROW(CellDbLock(dir / "linked_folder" / "new.db", "baked"), std::runtime_error);
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "new.db"));
  EXPECT_FALSE(std::filesystem::exists(dir / "new.db.lock"));
}

}  // namespace
}  // namespace cellbake

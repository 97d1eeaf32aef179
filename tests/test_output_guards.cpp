// Output paths are guarded (issue #14, items 1-3): a bake never adopts a
// geometry store or another file as its cell database, an ingest never
// replaces a cell database, a device, a directory, a pipe or a symbolic link,
// and temporaries of killed ingests are cleaned up. Issue #41: render (and
// every other output: storage/output_file.h) never writes over an input or
// any SQLite database, and a failed write leaves no partial file (item 1);
// the bake lock follows the database file, not the name it is reached by (item 6).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "pipeline/ingest.h"
#include "pipeline/scenes/scene_ply_writer.h"
#include "storage/cell_db.h"
#include "storage/cell_db_lock.h"
#include "storage/geometry_store.h"
#include "storage/output_file.h"
#include "tests/fixture_room_obj.h"
#include "tests/fixture_unprivileged.h"
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
  return "bake --store " + (dir / "s.db").string() +
         " --region=1,1,1,3,3,2 --cell-size 2 --face-size 16 --quiet --out " + out.string();
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
  for (const Case& c :
       {Case{dir / "cells.db", "is not a cellbake geometry store"}, Case{"/dev/null", "not a regular file"},
        Case{dir / "folder.db", "not a regular file"}, Case{dir / "pipe.db", "not a regular file"},
        Case{dir / "link.db", "symbolic link"}}) {
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
  EXPECT_EQ(test::run_cellbake("ingest " + obj.string() + " --store " + (dir / "s.db").string()).exit_code,
            0);
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
  const auto alive = temp(".tmp-", 1, true);             // pid 1 always runs
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

std::string file_bytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Names in `folder` that look like an output's temporary (NAME.tmp-PID-N).
std::vector<std::string> temporaries_in(const std::filesystem::path& folder) {
  std::vector<std::string> found;
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    if (entry.path().filename().string().find(".tmp-") != std::string::npos)
      found.push_back(entry.path().filename().string());
  return found;
}

// `render` of the baked dir/cells.db (store dir/s.db) from inside the box, small.
std::string render_into(const test::TempDir& dir, const std::filesystem::path& out) {
  return "render " + (dir / "cells.db").string() + " --store " + (dir / "s.db").string() +
         " --eye 2,2,1.5 --look 3,2,1.5 --size 24x24 --out " + out.string();
}

// `render` of the geometry store dir/s.db alone (its ground truth; the store
// is read without writing anything beside it), small.
std::string render_store_into(const test::TempDir& dir, const std::filesystem::path& out) {
  return "render " + (dir / "s.db").string() + " --size 24x24 --out " + out.string();
}

TEST(OutputGuards, RenderNeverWritesOverItsInputsOrAnyDatabase) {
  test::TempDir dir;
  make_store(dir);
  ASSERT_EQ(test::run_cellbake(bake_into(dir, dir / "cells.db")).exit_code, 0);
  std::filesystem::create_symlink(dir / "s.db", dir / "link.db");
  std::filesystem::create_hard_link(dir / "s.db", dir / "hard.db");
  std::filesystem::copy_file(dir / "s.db", dir / "copy.png");  // a database under any name
  const std::string store = file_bytes(dir / "s.db"), cells = file_bytes(dir / "cells.db");
  struct Case {
    std::filesystem::path out;
    const char* reason;
  };
  for (const Case& c :
       {Case{dir / "s.db", "is the input"}, Case{dir / "cells.db", "is the input"},
        Case{dir / "link.db", "is the input"}, Case{dir / "hard.db", "is the input"},
        Case{dir / "copy.png", "is an SQLite database"}, Case{"/dev/full", "not a regular file"}}) {
    const auto r = test::run_cellbake(render_into(dir, c.out));
    EXPECT_NE(r.exit_code, 0) << c.out << ": " << r.output;
    EXPECT_NE(r.output.find(c.out.string() + ": "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.reason), std::string::npos) << c.out << ": " << r.output;
  }
  // A store drawn alone refuses itself too, and a path's CSV may not land on a database.
  EXPECT_NE(test::run_cellbake(render_store_into(dir, dir / "s.db")).exit_code, 0);
  test::write_text(dir / "path.txt", "2 2 1.5 3 2 1.5\n");
  std::filesystem::copy_file(dir / "s.db", dir / "frames.csv");
  const auto path =
      test::run_cellbake("render " + (dir / "cells.db").string() + " --size 24x24 --path " +
                         (dir / "path.txt").string() + " --out " + (dir / "frames.png").string());
  EXPECT_NE(path.exit_code, 0) << path.output;
  EXPECT_NE(path.output.find("frames.csv: is an SQLite database"), std::string::npos) << path.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "frames_0000.png"));  // refused before any frame
  // Every input untouched, byte for byte, and nothing left behind.
  EXPECT_EQ(file_bytes(dir / "s.db"), store);
  EXPECT_EQ(file_bytes(dir / "cells.db"), cells);
  EXPECT_EQ(file_bytes(dir / "copy.png"), store);
  EXPECT_TRUE(std::filesystem::is_symlink(dir / "link.db"));
  EXPECT_TRUE(temporaries_in(dir.path()).empty());
  // A PNG of an earlier render is replaced as before.
  test::write_text(dir / "view.png", "an older image");
  const auto ok = test::run_cellbake(render_into(dir, dir / "view.png"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_EQ(file_bytes(dir / "view.png").substr(1, 3), "PNG");
}

TEST(OutputGuards, AFailedWriteIsAnErrorAndLeavesNoPartialFile) {
  test::TempDir dir;
  make_store(dir);
  test::write_text(dir / "old.png", "an older image");
  // Files may not grow past 0 bytes (write() fails with EFBIG: the signal is ignored).
  for (const auto& out : {dir / "old.png", dir / "new.png"}) {
    const auto r = test::run_shell("trap '' XFSZ; ulimit -f 0; exec " + std::string(CELLBAKE_BINARY) + " " +
                                   render_store_into(dir, out));
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find(out.string() + ": cannot write: File too large"), std::string::npos) << r.output;
  }
  EXPECT_EQ(file_bytes(dir / "old.png"), "an older image");
  EXPECT_FALSE(std::filesystem::exists(dir / "new.png"));
  EXPECT_TRUE(temporaries_in(dir.path()).empty());

  // A folder the user may not write to (as root: the command runs as nobody).
  std::string unprivileged;
  if (!test::unprivileged_prefix(unprivileged))
    GTEST_SKIP() << "root without setpriv: no unprivileged user to test with";
  std::filesystem::create_directory(dir / "ro");
  test::write_text(dir / "ro" / "old.png", "an older image");
  test::make_read_only_folder(dir / "ro");
  for (const auto& out : {dir / "ro" / "old.png", dir / "ro" / "new.png"}) {
    const auto r = test::run_cellbake_unprivileged(unprivileged, render_store_into(dir, out));
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find(out.string() + ": cannot create a temporary file"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("Permission denied"), std::string::npos) << r.output;
  }
  EXPECT_EQ(file_bytes(dir / "ro" / "old.png"), "an older image");
  EXPECT_FALSE(std::filesystem::exists(dir / "ro" / "new.png"));
  EXPECT_TRUE(temporaries_in(dir / "ro").empty());
  std::filesystem::permissions(dir / "ro", std::filesystem::perms::owner_all);
  // Written where it may be, the same render succeeds.
  const auto ok = test::run_cellbake(render_store_into(dir, dir / "old.png"));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_EQ(file_bytes(dir / "old.png").substr(1, 3), "PNG");
}

TEST(OutputGuards, OutputFileChecksAndCleansUpInProcess) {
  test::TempDir dir;
  make_store(dir);
  // Same file by identity, whatever the spelling; SQLite files by their header.
  std::filesystem::create_directory(dir / "sub");
  EXPECT_THROW(check_output_target(dir / "sub" / ".." / "s.db", {dir / "s.db"}), std::runtime_error);
  EXPECT_THROW(write_output_file(dir / "s.db", "x", {}), std::runtime_error);
  EXPECT_THROW(write_output_file("/dev/null", "x", {}), std::runtime_error);
  EXPECT_THROW(generate_scene_to_ply(SceneParams{}, dir / "s.db"), std::runtime_error);  // refused before generating
  // An output abandoned before commit leaves nothing; a committed one replaces the old file.
  test::write_text(dir / "a.txt", "old");
  {
    OutputFile out(dir / "a.txt", {});
    out.write("half");
  }
  EXPECT_EQ(file_bytes(dir / "a.txt"), "old");
  write_output_file(dir / "a.txt", "new", {dir / "s.db"});
  EXPECT_EQ(file_bytes(dir / "a.txt"), "new");
  EXPECT_TRUE(temporaries_in(dir.path()).empty());
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

// Issue #41, item 4: a cell database and its geometry store in a read-only
// folder (or on read-only media) can be read by every reading command —
// status, status --check, render (impostor and truth), verify, merge's reading
// of a shard — through SQLite's immutable open where the WAL's -shm file
// cannot be created; a -wal file with content there is an error naming it,
// never silently stale data. Tests run as root, which ignores folder
// permissions: the commands run as nobody (tests/fixture_unprivileged.h).
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

#include "pipeline/ingest.h"
#include "storage/cell_db.h"
#include "storage/sqlite_db.h"
#include "tests/fixture_room_obj.h"
#include "tests/fixture_unprivileged.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

namespace fs = std::filesystem;

// A small model ingested into FOLDER/s.db and baked into FOLDER/cells.db (a 2 x 2 x 1 grid of 2 m cells).
void bake_tiny(const fs::path& folder) {
  std::ostringstream o;
  int next = 1;
  test::obj_box(o, next, {0, 0, 0}, {4, 4, 3}, 2);
  test::write_text(folder / "box.obj", o.str());
  ingest_models({folder / "box.obj"}, folder / "s.db", IngestParams{},
                [](std::size_t n, const std::function<void(std::size_t)>& fn) {
                  for (std::size_t i = 0; i < n; ++i) fn(i);
                });
  const auto r = test::run_cellbake("bake --store " + (folder / "s.db").string() +
                                    " --region=1,1,1,3,3,2 --cell-size 2 --face-size 16 --quiet --out " +
                                    (folder / "cells.db").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

class ReadOnlyOpen : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!test::unprivileged_prefix(unprivileged_))
      GTEST_SKIP() << "root without setpriv: no unprivileged user";
    fs::create_directory(dir_ / "ro");
    bake_tiny(dir_ / "ro");
    test::make_writable_folder(dir_ / "out");
  }
  void TearDown() override {
    std::error_code ec;
    for (const char* folder : {"ro", "ro_wal"}) fs::permissions(dir_ / folder, fs::perms::owner_all, ec);
  }
  test::CommandResult run(const std::string& args) {
    return test::run_cellbake_unprivileged(unprivileged_, args);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  test::TempDir dir_;
  std::string unprivileged_;
};

TEST_F(ReadOnlyOpen, EveryReadingCommandReadsADatabaseInAReadOnlyFolder) {
  test::make_read_only_folder(dir_ / "ro");
  const std::string cells = path("ro/cells.db"), store = path("ro/s.db");
  for (const std::string& args :
       {"status " + cells, "status --check " + cells, "status " + store, "info " + store,
        "render " + cells + " --eye 2,2,1.5 --look 3,2,1.5 --size 24x24 --out " + path("out/impostor.png"),
        "render " + cells + " --mode truth --eye 2,2,1.5 --look 3,2,1.5 --size 24x24 --out " +
            path("out/truth.png"),
        "render " + store + " --size 24x24 --out " + path("out/store.png"),
        "verify --walk-seconds 0 " + cells + " --views-per-cell 1 --size 32x24 --quiet --threads 1 --report " +
            path("out/report"),
        "merge " + path("out/merged.db") + " " + cells}) {
    const auto r = run(args);
    EXPECT_EQ(r.exit_code, 0) << args << ":\n" << r.output;
    EXPECT_EQ(r.output.find("readonly database"), std::string::npos) << args << ":\n" << r.output;
  }
  EXPECT_TRUE(fs::exists(dir_ / "out" / "impostor.png"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "report" / "report.html"));
  // Nothing was created beside the database.
  for (const auto& entry : fs::directory_iterator(dir_ / "ro"))
    EXPECT_EQ(entry.path().filename().string().find("-shm"), std::string::npos) << entry.path();
  EXPECT_EQ(CellDb(dir_ / "out" / "merged.db", CellDb::Mode::read_only).cell_ids(),
            CellDb(dir_ / "ro" / "cells.db", CellDb::Mode::read_only).cell_ids());
}

TEST_F(ReadOnlyOpen, AWriteAheadLogWithContentInAReadOnlyFolderIsNamedNotIgnored) {
  // A copy taken while a writer's change sat in the -wal file (not yet checkpointed).
  fs::create_directory(dir_ / "ro_wal");
  {
    SqliteDb writer(dir_ / "ro" / "cells.db", SqliteDb::Mode::read_write_create);
    writer.exec("PRAGMA wal_autocheckpoint=0");
    writer.exec("INSERT OR REPLACE INTO meta(key, value) VALUES('note', 'in the wal only')");
    ASSERT_GT(fs::file_size(dir_ / "ro" / "cells.db-wal"), 0u);
    fs::copy_file(dir_ / "ro" / "cells.db", dir_ / "ro_wal" / "cells.db");
    fs::copy_file(dir_ / "ro" / "cells.db-wal", dir_ / "ro_wal" / "cells.db-wal");
  }
  test::make_read_only_folder(dir_ / "ro_wal");
  const auto r = run("status " + path("ro_wal/cells.db"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(path("ro_wal/cells.db-wal")), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not yet checkpointed"), std::string::npos) << r.output;
  // Where the folder is writable the same files read normally, the -wal's change included.
  fs::permissions(dir_ / "ro_wal", fs::perms::owner_all);
  EXPECT_EQ(CellDb(dir_ / "ro_wal" / "cells.db", CellDb::Mode::read_only).meta("note"), "in the wal only");
}

// Every connection opens through a percent-encoded URI: names with URI
// characters are the files they name, not queries or fragments.
TEST(SqliteUri, NamesWithUriCharactersOpenAsThemselves) {
  test::TempDir dir;
  fs::create_directory(dir / "a b?c#d%41");
  const fs::path file = dir / "a b?c#d%41" / "x?mode=ro&immutable=1#y.db";
  {
    SqliteDb db(file, SqliteDb::Mode::read_write_create);
    db.exec("CREATE TABLE t(v); INSERT INTO t VALUES(42)");
  }
  ASSERT_TRUE(fs::is_regular_file(file));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator{}), 1);  // nothing else made
  SqliteDb db(file, SqliteDb::Mode::read_only);
  EXPECT_FALSE(db.immutable());
  SqliteStatement s(db, "SELECT v FROM t");
  ASSERT_TRUE(s.step());
  EXPECT_EQ(s.column_int(0), 42);
}

}  // namespace
}  // namespace cellbake

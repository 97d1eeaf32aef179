// The viewer's cell cache (viewer/cell_cache.h) with its loader thread: misses
// queue a cell and never block, get_blocking waits for the decode, prefetches
// load in the background, the byte cap keeps the newest cell, absent and
// corrupt cells fail with their reason, cells baked while the database is
// viewed appear after an index refresh, and concurrent callers and a
// destruction while loading neither race nor hang (the tsan job runs these).
#include <gtest/gtest.h>

#include <chrono>
#include <sstream>
#include <thread>

#include "pipeline/ingest.h"
#include "storage/sqlite_db.h"
#include "tests/fixture_room_obj.h"
#include "tests/fixture_box_store.h"
#include "tests/test_support.h"
#include "viewer/cell_cache.h"

namespace cellbake {
namespace {

using namespace std::chrono_literals;

// A 4 x 4 x 3 m box with a pillar, and a 2 x 2 grid of 1.5 m cells (ids 1..4) baked small.
class CellCacheTest : public ::testing::Test {
 protected:
  void SetUp() override { test::ingest_box_with_pillar(dir_.path()); }
  std::filesystem::path db() const { return dir_ / "cells.db"; }
  void bake(const std::string& extra = "") {
    const auto r = test::run_cellbake("bake --store " + (dir_ / "s.db").string() +
                                      " --region=0.5,0.5,1,3.5,3.5,1 --cell-size 1.5 --face-size 16 --quiet "
                                      "--threads 1 --out " + db().string() + " " + extra);
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  // Polls `done` for up to `limit`; true once it holds.
  template <class Done>
  static bool eventually(Done done, std::chrono::milliseconds limit = 60s) {
    const auto until = std::chrono::steady_clock::now() + limit;
    while (!done()) {
      if (std::chrono::steady_clock::now() > until) return false;
      std::this_thread::sleep_for(5ms);
    }
    return true;
  }
  test::TempDir dir_;
};

TEST_F(CellCacheTest, AMissQueuesTheCellAndGetBlockingDecodesIt) {
  bake();
  CellCache cache(db());
  EXPECT_EQ(cache.index()->cells().size(), 4u);
  const auto first = cache.get_blocking(2);
  ASSERT_NE(first, nullptr) << cache.failure(2);
  EXPECT_EQ(first->id, 2);
  EXPECT_FALSE(first->cull_box.empty());
  EXPECT_EQ(cache.get(2), first);  // a hit: the same decoded cell
  EXPECT_EQ(cache.get(3), nullptr);  // a miss never blocks
  ASSERT_NE(cache.get_blocking(3), nullptr);
  const CellCacheStats s = cache.stats();
  EXPECT_EQ(s.loads, 2u);
  EXPECT_EQ(s.cells, 2u);
  EXPECT_GE(s.hits, 1u);
  EXPECT_GE(s.misses, 2u);
  EXPECT_GT(s.bytes, 0u);
}

TEST_F(CellCacheTest, PrefetchedCellsLoadInTheBackground) {
  bake();
  CellCache cache(db());
  cache.prefetch({1, 2, 3, 4});
  ASSERT_TRUE(eventually([&] { return cache.stats().loads == 4; }));
  for (std::int64_t id = 1; id <= 4; ++id) {
    const auto cell = cache.get(id);
    ASSERT_NE(cell, nullptr) << id;
    EXPECT_EQ(cell->id, id);
  }
  EXPECT_EQ(cache.stats().hits, 4u);
  cache.prefetch({1, 2});  // cached: ignored
  std::this_thread::sleep_for(50ms);
  EXPECT_EQ(cache.stats().loads, 4u);
}

TEST_F(CellCacheTest, TheByteCapKeepsTheNewestCell) {
  bake();
  CellCacheParams params;
  params.max_bytes = 1;
  CellCache cache(db(), params);
  ASSERT_NE(cache.get_blocking(1), nullptr);
  ASSERT_NE(cache.get_blocking(2), nullptr);
  EXPECT_EQ(cache.stats().cells, 1u);
  EXPECT_EQ(cache.stats().evictions, 1u);
  EXPECT_NE(cache.get(2), nullptr);
  EXPECT_EQ(cache.get(1), nullptr);  // evicted: a miss again
}

TEST_F(CellCacheTest, AbsentAndCorruptCellsFailWithTheirReason) {
  bake();
  {
    SqliteDb d(db().string(), SqliteDb::Mode::read_write_create);
    d.exec("update cells set near_chunks = x'0102' where id = 4");
  }
  CellCache cache(db());
  EXPECT_EQ(cache.get_blocking(999), nullptr);
  EXPECT_FALSE(cache.failure(999).empty());
  EXPECT_EQ(cache.get_blocking(4), nullptr);
  EXPECT_NE(cache.failure(4).find("cell 4"), std::string::npos) << cache.failure(4);
  EXPECT_EQ(cache.get(4), nullptr);  // failed cells are not queued again
  EXPECT_NE(cache.get_blocking(1), nullptr);  // the others still load
  EXPECT_EQ(cache.failure(1), "");
  EXPECT_EQ(cache.stats().failures, 2u);
}

TEST_F(CellCacheTest, CellsBakedWhileViewedAppearAfterAnIndexRefresh) {
  bake("--cells 1");
  CellCacheParams params;
  params.index_refresh_seconds = 0.05;
  CellCache cache(db(), params);
  ASSERT_NE(cache.get_blocking(1), nullptr);
  EXPECT_EQ(cache.get_blocking(3), nullptr);  // not baked yet
  bake("--cells 3");
  EXPECT_TRUE(eventually([&] { return cache.get(3) != nullptr; })) << cache.failure(3);
  EXPECT_EQ(cache.failure(3), "");
  EXPECT_TRUE(cache.index()->find(3) && cache.index()->find(3)->done);
}

TEST_F(CellCacheTest, ConcurrentCallersGetTheirCellsAndDestructionWhileLoadingEnds) {
  bake();
  {
    CellCacheParams params;
    params.max_bytes = 1;  // constant eviction and reloading
    params.index_refresh_seconds = 0.01;
    CellCache cache(db(), params);
    std::vector<std::thread> threads;
    std::vector<int> wrong(4, 0);
    for (int t = 0; t < 4; ++t)
      threads.emplace_back([&, t] {
        for (int i = 0; i < 40; ++i) {
          const std::int64_t id = 1 + (t + i) % 4;
          cache.prefetch({1 + (id % 4)});
          const auto cell = i % 3 == 0 ? cache.get(id) : cache.get_blocking(id);
          if (cell && cell->id != id) ++wrong[std::size_t(t)];
          if (i % 3 != 0 && !cell) ++wrong[std::size_t(t)];
          (void)cache.stats();
          (void)cache.index();
        }
      });
    for (auto& t : threads) t.join();
    for (int w : wrong) EXPECT_EQ(w, 0);
    EXPECT_EQ(cache.stats().failures, 0u);
    cache.prefetch({1, 2, 3, 4});  // still loading when the cache goes
  }
  // Destroyed with a queue: the thread stopped and was joined (reaching here).
  SUCCEED();
}

}  // namespace
}  // namespace cellbake

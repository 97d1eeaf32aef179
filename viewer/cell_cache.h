// Decoded view cells for the interactive viewer: a background thread loads and
// decodes requested cells (and prefetched neighbours) from the cell database
// into an LRU cache capped in bytes, and periodically re-reads the cell index
// so a database still being baked fills in while it is viewed.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "viewer/cell_index.h"
#include "viewer/decoded_cell.h"

namespace cellbake {

struct CellCacheParams {
  std::size_t max_bytes = std::size_t{1} << 30;  // decoded cells kept (host memory); the newest is always kept
  double index_refresh_seconds = 2.0;            // how often the cell index is re-read
  const ChunkSource* source = nullptr;  // the cells' geometry store (thread-safe): far pieces cut on the loader thread (decode_cell)
  // With `source`: after decoding a cell, also load its near and whole far
  // chunks through `source` on the loader thread, so that a store with a
  // chunk cache (GeometryStore) has them decoded before the drawing thread asks.
  bool load_chunks = false;
  // The loader thread's nice value (Linux; 0 leaves it): above the drawing
  // threads', so that decoding ahead waits for a frame rather than slowing it
  // (llvmpipe rasterises on every core).
  int loader_nice = 10;
};

struct CellCacheStats {
  std::uint64_t hits = 0, misses = 0, loads = 0, failures = 0, evictions = 0;
  std::size_t cells = 0, bytes = 0;
  std::size_t peak_bytes = 0;  // the most `bytes` has been
  std::size_t max_bytes = 0;   // the cap (CellCacheParams::max_bytes)
};

class CellCache {
 public:
  // Opens `database` read-only on its own thread (reads the index once before
  // returning). Throws std::runtime_error when the database cannot be opened.
  CellCache(const std::filesystem::path& database, CellCacheParams params = {});
  ~CellCache();  // stops and joins the thread
  CellCache(const CellCache&) = delete;
  CellCache& operator=(const CellCache&) = delete;

  // The decoded cell if cached (a hit), else nullptr and the cell is queued
  // first (a miss). Never blocks on loading.
  std::shared_ptr<const DecodedCell> get(std::int64_t id);
  // Waits until the cell is cached or has failed (queueing it again if
  // another load evicted it first); nullptr when it failed.
  std::shared_ptr<const DecodedCell> get_blocking(std::int64_t id);
  // Replaces the cells queued by earlier prefetch calls with `ids`, queued in
  // this order behind any requested ones (cached or failed ones: ignored), so
  // a viewer's latest ranking of its neighbours decides what loads next.
  void prefetch(const std::vector<std::int64_t>& ids);
  // The decoded cell if cached, else nullptr; neither a hit nor a miss, queues
  // nothing and leaves the cell's recency as it is.
  std::shared_ptr<const DecodedCell> peek(std::int64_t id) const;
  // The failure message of a cell that could not be loaded or decoded ("" if none).
  std::string failure(std::int64_t id) const;
  // The latest cell index.
  std::shared_ptr<const CellIndex> index() const;
  CellCacheStats stats() const;

 private:
  void run();
  void store(std::int64_t id, std::shared_ptr<const DecodedCell> cell);

  std::filesystem::path database_;
  CellCacheParams params_;
  mutable std::mutex mutex_;
  std::condition_variable wake_, loaded_;
  std::deque<std::int64_t> queue_;
  std::map<std::int64_t, std::shared_ptr<const DecodedCell>> cells_;
  std::map<std::int64_t, std::list<std::int64_t>::iterator> recency_;
  std::list<std::int64_t> lru_;  // front = most recent
  std::map<std::int64_t, std::string> failures_;
  std::set<std::int64_t> prefetched_;  // queued by prefetch(), not requested
  std::set<std::int64_t> missing_;  // failed because absent or not baked: retried once the index shows them done
  std::int64_t loading_ = 0;        // the cell the loader thread is reading (0: none)
  std::shared_ptr<const CellIndex> index_;
  CellCacheStats stats_;
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace cellbake

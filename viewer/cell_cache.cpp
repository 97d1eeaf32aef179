#include "viewer/cell_cache.h"

#include <algorithm>
#include <chrono>

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include "storage/cell_db.h"

namespace cellbake {

CellCache::CellCache(const std::filesystem::path& database, CellCacheParams params)
    : database_(database), params_(params) {
  {
    CellDb db(database_, CellDb::Mode::read_only);
    index_ = std::make_shared<const CellIndex>(db);
  }
  worker_ = std::thread([this] { run(); });
}

CellCache::~CellCache() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  loaded_.notify_all();
  worker_.join();
}

std::shared_ptr<const DecodedCell> CellCache::get(std::int64_t id) {
  std::lock_guard lock(mutex_);
  if (auto it = cells_.find(id); it != cells_.end()) {
    ++stats_.hits;
    lru_.splice(lru_.begin(), lru_, recency_.at(id));
    return it->second;
  }
  ++stats_.misses;
  if (!failures_.contains(id)) {
    std::erase(queue_, id);
    prefetched_.erase(id);
    queue_.push_front(id);
    wake_.notify_all();
  }
  return nullptr;
}

std::shared_ptr<const DecodedCell> CellCache::get_blocking(std::int64_t id) {
  if (auto cell = get(id)) return cell;
  std::unique_lock lock(mutex_);
  while (true) {
    if (auto it = cells_.find(id); it != cells_.end()) return it->second;
    if (failures_.contains(id) || stop_) return nullptr;
    // Not cached: not loaded yet, or loaded and already evicted by the loads
    // of other cells before this thread woke. Queued first unless it is
    // (also when only prefetched: a later prefetch() would drop it).
    if (loading_ != id && (queue_.empty() || queue_.front() != id)) {
      std::erase(queue_, id);
      prefetched_.erase(id);
      queue_.push_front(id);
      wake_.notify_all();
    }
    loaded_.wait(lock);
  }
}

void CellCache::prefetch(const std::vector<std::int64_t>& ids) {
  std::lock_guard lock(mutex_);
  std::erase_if(queue_, [&](std::int64_t id) { return prefetched_.contains(id); });
  prefetched_.clear();
  for (std::int64_t id : ids)
    if (!cells_.contains(id) && !failures_.contains(id) && std::find(queue_.begin(), queue_.end(), id) == queue_.end()) {
      queue_.push_back(id);
      prefetched_.insert(id);
    }
  wake_.notify_all();
}

std::shared_ptr<const DecodedCell> CellCache::peek(std::int64_t id) const {
  std::lock_guard lock(mutex_);
  const auto it = cells_.find(id);
  return it == cells_.end() ? nullptr : it->second;
}

std::string CellCache::failure(std::int64_t id) const {
  std::lock_guard lock(mutex_);
  auto it = failures_.find(id);
  return it == failures_.end() ? std::string() : it->second;
}

std::shared_ptr<const CellIndex> CellCache::index() const {
  std::lock_guard lock(mutex_);
  return index_;
}

CellCacheStats CellCache::stats() const {
  std::lock_guard lock(mutex_);
  CellCacheStats s = stats_;
  s.cells = cells_.size();
  s.max_bytes = params_.max_bytes;
  return s;
}

void CellCache::store(std::int64_t id, std::shared_ptr<const DecodedCell> cell) {
  // Called with mutex_ held.
  const std::size_t bytes = cell->bytes();
  cells_[id] = std::move(cell);
  lru_.push_front(id);
  recency_[id] = lru_.begin();
  stats_.bytes += bytes;
  ++stats_.loads;
  while (stats_.bytes > params_.max_bytes && lru_.size() > 1) {
    const std::int64_t victim = lru_.back();
    lru_.pop_back();
    recency_.erase(victim);
    stats_.bytes -= cells_.at(victim)->bytes();
    cells_.erase(victim);
    ++stats_.evictions;
  }
  stats_.peak_bytes = std::max(stats_.peak_bytes, stats_.bytes);
}

void CellCache::run() {
#ifdef __linux__
  // Per thread on Linux: lowers this thread alone (failure leaves it as it was).
  if (params_.loader_nice > 0) setpriority(PRIO_PROCESS, id_t(syscall(SYS_gettid)), params_.loader_nice);
#endif
  using Clock = std::chrono::steady_clock;
  auto last_refresh = Clock::now();
  std::unique_ptr<CellDb> db;
  const auto refresh_interval = std::chrono::duration<double>(params_.index_refresh_seconds);
  while (true) {
    std::int64_t id = 0;
    {
      std::unique_lock lock(mutex_);
      wake_.wait_for(lock, refresh_interval, [&] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      if (!queue_.empty()) {
        id = queue_.front();
        queue_.pop_front();
        prefetched_.erase(id);
        if (cells_.contains(id)) id = 0;
        loading_ = id;
      }
    }
    try {
      if (!db) db = std::make_unique<CellDb>(database_, CellDb::Mode::read_only);
      if (Clock::now() - last_refresh >= refresh_interval) {
        auto fresh = std::make_shared<const CellIndex>(*db);
        last_refresh = Clock::now();
        std::lock_guard lock(mutex_);
        index_ = std::move(fresh);
        // Cells that were missing (still baking) may exist now.
        for (auto it = missing_.begin(); it != missing_.end();) {
          const CellEntry* entry = index_->find(*it);
          if (entry && entry->done) {
            failures_.erase(*it);
            it = missing_.erase(it);
          } else {
            ++it;
          }
        }
      }
    } catch (const std::exception&) {
      db.reset();  // retried on the next round
    }
    if (id == 0) continue;
    std::shared_ptr<const DecodedCell> cell;
    std::string error;
    bool missing = false;
    try {
      if (!db) throw std::runtime_error("cell database " + database_.string() + " cannot be opened");
      const auto row = db->get_cell(id, true);
      // Not there or not baked yet: retried once the index shows it done.
      missing = !row || row->status != "done";
      if (!row) throw std::runtime_error("cell " + std::to_string(id) + " is not in the database (yet)");
      if (missing) throw std::runtime_error("cell " + std::to_string(id) + " is not baked yet (status " + row->status + ")");
      cell = std::make_shared<const DecodedCell>(decode_cell(*row, params_.source));
      if (params_.source && params_.load_chunks) {
        try {
          for (std::int64_t chunk : cell->near_ids) params_.source->load(chunk);
          for (std::int64_t chunk : cell->far_whole_ids) params_.source->load(chunk);
        } catch (const std::exception&) {
          // A chunk the store lacks: the draw reports it (and falls back to the truth).
        }
      }
    } catch (const std::exception& e) {
      error = e.what();
    }
    {
      std::lock_guard lock(mutex_);
      loading_ = 0;
      if (cell) {
        store(id, std::move(cell));
      } else {
        failures_[id] = error;
        if (missing) missing_.insert(id);
        ++stats_.failures;
      }
    }
    loaded_.notify_all();
  }
}

}  // namespace cellbake

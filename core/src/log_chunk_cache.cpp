// ChunkCache (log_reader.hpp): decompressed log chunks shared by a reader's scan and reads;
// decompressAhead: the chunks of an indexed log decompressed in parallel at opening.
#include <algorithm>
#include <deque>
#include <thread>

#include "log_reader.hpp"

namespace cs::logio {

ChunkData ChunkCache::get(uint64_t key, const Load& load) {
  std::promise<ChunkData> promise;
  std::unique_lock<std::mutex> lock(mutex_);
  if (const auto it = entries_.find(key); it != entries_.end()) {
    it->second.used = ++clock_;
    const std::shared_future<ChunkData> chunk = it->second.chunk;
    lock.unlock();  // wait (if another thread is decompressing it) without the lock
    return chunk.get();
  }
  entries_[key] = Entry{promise.get_future().share(), 0, ++clock_};
  ++loads_;
  lock.unlock();
  ChunkData chunk;
  try {
    chunk = load();
  } catch (...) {
    promise.set_exception(std::current_exception());  // those waiting see the error too
    lock.lock();
    entries_.erase(key);  // not kept: a later read tries again and names the error again
    throw;
  }
  promise.set_value(chunk);
  lock.lock();
  if (const auto it = entries_.find(key); it != entries_.end() && chunk.owner) {
    it->second.bytes = chunk.size;
    bytes_ += chunk.size;
    evict(key);
  }
  return chunk;
}

void ChunkCache::keep(uint64_t key, const ChunkData& chunk) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!chunk.owner || entries_.count(key) || bytes_ + chunk.size > budget_) return;
  std::promise<ChunkData> ready;
  ready.set_value(chunk);
  entries_[key] = Entry{ready.get_future().share(), chunk.size, ++clock_};
  bytes_ += chunk.size;
}

// Least recently used first; chunks still being decompressed (bytes 0) and `keep` stay.
// Readers holding an evicted chunk keep it alive through its shared owner.
void ChunkCache::evict(uint64_t keep) {
  while (bytes_ > budget_) {
    auto oldest = entries_.end();
    for (auto it = entries_.begin(); it != entries_.end(); ++it)
      if (it->first != keep && it->second.bytes && (oldest == entries_.end() || it->second.used < oldest->second.used))
        oldest = it;
    if (oldest == entries_.end()) return;
    bytes_ -= oldest->second.bytes;
    entries_.erase(oldest);
  }
}

void decompressAhead(const std::vector<uint64_t>& chunks, const std::function<ChunkData(uint64_t)>& decompress,
                     const std::function<void(uint64_t, const ChunkData&)>& use, unsigned threads) {
  if (threads == 0) threads = std::clamp(std::thread::hardware_concurrency(), 1u, 8u);
  std::deque<std::future<ChunkData>> ahead;  // chunks next..next+ahead.size()-1, in flight
  size_t next = 0, started = 0;
  // The window: `threads` chunks decompressing while one is used.
  while (next < chunks.size()) {
    while (started < chunks.size() && ahead.size() < threads) {
      const uint64_t offset = chunks[started++];
      ahead.push_back(std::async(std::launch::async, [&decompress, offset] { return decompress(offset); }));
    }
    const ChunkData chunk = ahead.front().get();  // rethrows its error, at its turn
    ahead.pop_front();
    use(chunks[next++], chunk);
  }
}

}  // namespace cs::logio

// The host's thread pool and the parallel host copy (host_threads.hpp).
#include "curvestereo/host_threads.hpp"

#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <thread>

namespace cs {

namespace {

// A persistent pool: the CPU backend's kernels run thousands of times per frame, too
// often to start threads for each. Worker t (the caller is worker 0) takes parts t, t + n,
// t + 2n, ...
class ThreadPool {
 public:
  ThreadPool() : workers_(int(std::max(1u, std::thread::hardware_concurrency()))) {
    for (int t = 1; t < workers_; ++t) threads_.emplace_back([this, t] { serve(t); });
  }
  ~ThreadPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    for (auto& th : threads_) th.join();
  }

  void run(int count, const std::function<void(int)>& body) {
    std::unique_lock<std::mutex> lock(mutex_);
    body_ = &body;
    count_ = count;
    pending_ = workers_ - 1;
    ++generation_;
    lock.unlock();
    wake_.notify_all();
    parts(0, count, body);
    lock.lock();
    finished_.wait(lock, [this] { return pending_ == 0; });
    body_ = nullptr;
  }

  int workers() const { return workers_; }

 private:
  void parts(int t, int count, const std::function<void(int)>& body) const {
    for (int i = t; i < count; i += workers_) body(i);
  }

  void serve(int t) {
    unsigned seen = 0;
    for (;;) {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      const std::function<void(int)>* body = body_;
      const int count = count_;
      lock.unlock();
      parts(t, count, *body);
      lock.lock();
      if (--pending_ == 0) finished_.notify_one();
    }
  }

  const int workers_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  const std::function<void(int)>* body_ = nullptr;
  int count_ = 0, pending_ = 0;
  unsigned generation_ = 0;
  bool stopping_ = false;
};

ThreadPool& pool() {
  static ThreadPool instance;
  return instance;
}

std::mutex poolInUse;

// Below this a copy is one piece: a piece should take longer than waking a thread
// (~10 us; 256 KiB is ~20 us of one core's memcpy).
constexpr size_t kPieceBytes = size_t(256) << 10;
// The memory's bandwidth is reached well before every core of a large host copies.
constexpr int kMaxCopyThreads = 8;

}  // namespace

void parallelFor(int count, const std::function<void(int)>& body) {
  std::unique_lock<std::mutex> lock(poolInUse, std::try_to_lock);
  if (!lock.owns_lock() || pool().workers() == 1 || count < 2) {
    for (int i = 0; i < count; ++i) body(i);
    return;
  }
  pool().run(count, body);
}

int copyPieces(size_t bytes) {
  return int(std::max<size_t>(1, std::min<size_t>(kMaxCopyThreads, bytes / kPieceBytes)));
}

void copyHost(const std::vector<HostCopy>& copies) {
  size_t total = 0;
  for (const HostCopy& c : copies) total += c.bytes;
  const int threads = copyPieces(total);
  if (threads < 2) {
    for (const HostCopy& c : copies) std::memcpy(c.dst, c.src, c.bytes);
    return;
  }
  // Part t copies the bytes [t total / threads, (t + 1) total / threads) of the list's
  // concatenation: one contiguous range, crossing from one copy into the next.
  parallelFor(threads, [&](int t) {
    size_t begin = total * size_t(t) / size_t(threads), end = total * size_t(t + 1) / size_t(threads);
    size_t start = 0;  // of the current copy within the concatenation
    for (const HostCopy& c : copies) {
      const size_t from = std::max(begin, start), to = std::min(end, start + c.bytes);
      if (from < to)
        std::memcpy(static_cast<char*>(c.dst) + (from - start), static_cast<const char*>(c.src) + (from - start),
                    to - from);
      start += c.bytes;
      if (start >= end) break;
    }
  });
}

}  // namespace cs

#include "curvestereo/parallel.hpp"

#include <algorithm>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace cs::detail {

namespace {

// Set while a thread runs a parallelFor body: a body that calls parallelFor again (a copy
// inside a kernel's row) runs that loop itself, and never try-locks a mutex it holds.
thread_local bool insideBody = false;

class WorkerPool {
 public:
  WorkerPool() : workers_(int(std::max(1u, std::thread::hardware_concurrency()))) {
    for (int t = 1; t < workers_; ++t) threads_.emplace_back([this, t] { serve(t); });
  }
  ~WorkerPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    for (auto& th : threads_) th.join();
  }

  // Only the first min(n, T) workers take part, and only they are waited for: a short loop
  // (a 700 KB copy in three pieces) does not wait for every thread of a large machine to
  // wake. A worker that wakes late reads the latest generation's state, under the lock.
  void run(int n, const std::function<void(int)>& body) {
    std::unique_lock<std::mutex> lock(mutex_);
    body_ = &body;
    n_ = n;
    const int participants = participants_ = std::min(n, workers_);
    pending_ = participants - 1;
    ++generation_;
    lock.unlock();
    wake_.notify_all();
    items(0, n, participants, body);
    lock.lock();
    finished_.wait(lock, [this] { return pending_ == 0; });
    body_ = nullptr;
  }

  int workers() const { return workers_; }

 private:
  void items(int t, int n, int participants, const std::function<void(int)>& body) const {
    insideBody = true;
    for (int i = t; i < n; i += participants) body(i);
    insideBody = false;
  }

  void serve(int t) {
    unsigned seen = 0;
    for (;;) {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
      if (t >= participants_) continue;
      const std::function<void(int)>* body = body_;
      const int n = n_, participants = participants_;
      lock.unlock();
      items(t, n, participants, *body);
      lock.lock();
      if (--pending_ == 0) finished_.notify_one();
    }
  }

  const int workers_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, finished_;
  const std::function<void(int)>* body_ = nullptr;
  int n_ = 0, participants_ = 0, pending_ = 0;
  unsigned generation_ = 0;
  bool stopping_ = false;
};

WorkerPool& pool() {
  static WorkerPool instance;
  return instance;
}

std::mutex poolInUse;

}  // namespace

int parallelWorkers() { return pool().workers(); }

void parallelFor(int n, const std::function<void(int)>& body, int minimum) {
  std::unique_lock<std::mutex> lock(poolInUse, std::defer_lock);
  if (n < minimum || insideBody || pool().workers() == 1 || !lock.try_lock()) {
    for (int i = 0; i < n; ++i) body(i);
    return;
  }
  pool().run(n, body);
}

void parallelPieces(size_t n, size_t piece, const std::function<void(size_t, size_t)>& body) {
  parallelFor(int((n + piece - 1) / piece), [&](int k) {
    const size_t begin = size_t(k) * piece;
    body(begin, std::min(n, begin + piece));
  });
}

}  // namespace cs::detail

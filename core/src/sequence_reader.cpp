// SequenceReader (sequence.hpp): a sequence's frames read ahead on background threads.
#include <algorithm>
#include <chrono>
#include <exception>

#include "curvestereo/sequence.hpp"

namespace cs {

struct SequenceReader::Slot {
  ImageF left, right;
  std::exception_ptr error;
  double ms = 0;
};

namespace {
double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

SequenceReader::SequenceReader(const Sequence& sequence, int threads, size_t first, size_t end)
    : sequence_(sequence), end_(std::min(end, sequence.frames().size())) {
  nextToRead_ = nextToHand_ = std::min(first, end_);
  if (threads <= 0) threads = int(std::clamp(std::thread::hardware_concurrency() / 4, 1u, 4u));
  // One frame more than readers: each reader has one in hand while the caller takes the next.
  ahead_ = size_t(threads) + 1;
  const size_t n = std::min<size_t>(size_t(threads), end_ - nextToRead_);
  for (size_t t = 0; t < n; ++t) workers_.emplace_back([this] { work(); });
}

SequenceReader::~SequenceReader() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  for (std::thread& t : workers_) t.join();
}

// Each reader takes the next frame within the window ahead of the caller, reads it without
// the lock, and files it (or its error) in its slot.
void SequenceReader::work() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    changed_.wait(lock, [&] { return stopping_ || (nextToRead_ < end_ && nextToRead_ < nextToHand_ + ahead_); });
    if (stopping_) return;
    const size_t i = nextToRead_++;
    Slot slot;
    if (!spare_.empty()) {  // the caller's last images: no fresh allocation (and page faults) a frame
      std::swap(slot.left, spare_.back().first);
      std::swap(slot.right, spare_.back().second);
      spare_.pop_back();
    }
    lock.unlock();
    const auto t0 = std::chrono::steady_clock::now();
    try {
      sequence_.load(i, slot.left, slot.right);
    } catch (...) {
      slot.error = std::current_exception();
    }
    slot.ms = msSince(t0);
    lock.lock();
    slots_[i] = std::move(slot);
    changed_.notify_all();
  }
}

bool SequenceReader::next(size_t& index, ImageF& left, ImageF& right) {
  if (nextToHand_ >= end_) return false;
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return slots_.count(nextToHand_) > 0; });
  (handed_++ ? waitedMs_ : firstWaitMs_) += msSince(t0);
  const auto it = slots_.find(nextToHand_);
  Slot slot = std::move(it->second);
  slots_.erase(it);
  index = nextToHand_++;
  if (slot.error) {  // the frames after an unreadable one are not handed out, nor read on
    nextToHand_ = end_;
    stopping_ = true;
  } else {
    std::swap(left, slot.left);
    std::swap(right, slot.right);
    spare_.emplace_back(std::move(slot.left), std::move(slot.right));
  }
  readMs_ += slot.ms;
  lock.unlock();
  changed_.notify_all();  // the window moved: a reader may take the next frame
  if (slot.error) std::rethrow_exception(slot.error);
  return true;
}

}  // namespace cs

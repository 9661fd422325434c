// The host's threads, shared by every backend: a persistent pool for work split into
// independent parts (the CPU backend's rows, the GPU backends' large host copies).
#pragma once
#include <cstddef>
#include <functional>
#include <vector>

namespace cs {

// Runs body(i) for every i in [0, count), split across the host's hardware threads (the
// caller among them). Parts must write disjoint memory, so results do not depend on the
// number of threads. One caller at a time uses the pool: another thread calling meanwhile
// (a second Stereo) runs its parts on its own thread rather than waiting.
void parallelFor(int count, const std::function<void(int)>& body);

// One host-to-host copy of `bytes` bytes; source and destination do not overlap.
struct HostCopy {
  void* dst;
  const void* src;
  size_t bytes;
};
// How many contiguous pieces a host copy of `bytes` bytes is split into over the pool (1:
// the calling thread alone, where waking threads would cost more than they save).
int copyPieces(size_t bytes);
// Every copy of the list, large ones split into contiguous pieces over the pool: a single
// thread's memcpy does not reach the memory's bandwidth (a 2.7 MB image is ~0.25 ms on
// one core), and a frame's downloads are several such images. The bytes are the same as
// memcpy's; small lists are copied on the calling thread (waking the pool costs more).
void copyHost(const std::vector<HostCopy>& copies);

}  // namespace cs

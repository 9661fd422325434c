// One process-wide pool of persistent threads for the host-side loops that run every frame:
// the CPU backend's kernels (thousands a frame, too often to start threads for each) and
// the GPU backends' copies between pinned staging memory and the caller's images.
// Internal, as backend.hpp.
#pragma once
#include <cstddef>
#include <functional>

namespace cs::detail {

// Runs body(i) for every i in [0, n): with T = min(n, threads), worker t (the caller is
// worker 0) takes t, t + T, t + 2T, ... in that order, so items that become ready in order
// are taken in order.
// Serial in the caller when n < minimum, when the machine has one hardware thread, or when
// another caller holds the pool (a second frame in another thread runs on its own thread
// rather than waiting), and when called from inside a body. Results must not depend on the
// split. body must not throw: a worker has no caller to throw to.
void parallelFor(int n, const std::function<void(int)>& body, int minimum = 2);

// body(begin, end) for consecutive pieces [k * piece, min(n, (k + 1) * piece)) of a range of
// n items, on the pool. Fixed pieces: a reduction that combines the pieces' results in order
// gets the same value on any number of threads.
void parallelPieces(size_t n, size_t piece, const std::function<void(size_t, size_t)>& body);

// The pool's threads, the caller included (the machine's hardware threads).
int parallelWorkers();

}  // namespace cs::detail

// Pairing two cameras' frames by timestamp, shared by ASL folders and logs (sequence_io.cpp).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace cs::detail {

struct TimePairs {
  std::vector<std::pair<size_t, size_t>> pairs;  // (left, right) indexes, in left order
  std::vector<size_t> leftAlone, rightAlone;     // frames without a partner
};

// Mutual nearest neighbours within toleranceMs: one-to-one, and a frame missing from one
// camera cannot pull its neighbour's partner away. Both lists sorted ascending.
TimePairs pairByTime(const std::vector<int64_t>& left, const std::vector<int64_t>& right, double toleranceMs);

std::string msText(double ms);  // "1 ms"

}  // namespace cs::detail

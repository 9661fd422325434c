// The time of one stage of a frame (cs::DepthResult::stages).
#pragma once
#include <string>

namespace cs {

struct StageTime {
  std::string name;
  double ms = 0;
};

}  // namespace cs

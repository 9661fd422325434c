#include "cpu_backend.hpp"

namespace cs::cpu {

void warp(const View& dst, const View& src, const View& flow) {
  parallelRows(dst.height, [&](int y) {
    for (int x = 0; x < dst.width; ++x) {
      float sx = float(x) + flow.at(x, y, 0), sy = float(y) + flow.at(x, y, 1);
      for (int c = 0; c < dst.channels; ++c) dst.at(x, y, c) = sampleBilinear(src, sx, sy, c);
    }
  });
}

}  // namespace cs::cpu

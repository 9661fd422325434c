#include <algorithm>

#include "cpu_backend.hpp"

namespace cs::cpu {

// 3x3 median over the masked neighbours; removes isolated outliers of u after each warp.
void median(const View& dst, const View& src, const View& mask) {
  parallelRows(dst.height, [&](int y) {
    for (int x = 0; x < dst.width; ++x) {
      if (!masked(mask, x, y)) {
        dst.at(x, y) = src.at(x, y);
        continue;
      }
      float values[9];
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (masked(mask, x + dx, y + dy)) values[n++] = src.at(x + dx, y + dy);
      std::nth_element(values, values + n / 2, values + n);
      float upper = values[n / 2];
      // Even counts take the mean of the two middle values, so the result is unique.
      if (n % 2 == 0) {
        float lower = *std::max_element(values, values + n / 2);
        upper = 0.5f * (lower + upper);
      }
      dst.at(x, y) = upper;
    }
  });
}

}  // namespace cs::cpu

// Local contrast normalisation: each pixel's grey level relative to the mean and spread of
// its neighbourhood. A gain, an offset or a shading that is nearly constant over the
// window (vignetting, exposure, the two sensors' responses) cancels; epsilon keeps noise
// in flat regions from being stretched to full contrast.
#include <cmath>

#include "cpu_backend.hpp"

namespace cs::cpu {

void normalise(const View& dst, const View& moments, const View& src, const View& mask, const NormaliseParams& p) {
  const int r = p.radius;
  // Horizontal pass: masked, weighted sums of 1, I and I^2 along the row.
  parallelRows(src.height, [&](int y) {
    for (int x = 0; x < src.width; ++x) {
      float s0 = 0.f, s1 = 0.f, s2 = 0.f;
      for (int i = -r; i <= r; ++i) {
        if (!masked(mask, x + i, y)) continue;
        const float t = p.taps[i + r], v = src.at(x + i, y);
        s0 += t;
        s1 += t * v;
        s2 += t * (v * v);
      }
      moments.at(x, y, 0) = s0, moments.at(x, y, 1) = s1, moments.at(x, y, 2) = s2;
    }
  });
  // Vertical pass, then the normalised value.
  parallelRows(src.height, [&](int y) {
    for (int x = 0; x < src.width; ++x) {
      if (!masked(mask, x, y)) {
        dst.at(x, y) = 0.f;
        continue;
      }
      float s0 = 0.f, s1 = 0.f, s2 = 0.f;
      for (int j = -r; j <= r; ++j) {
        if (y + j < 0 || y + j >= src.height) continue;
        const float t = p.taps[j + r];
        s0 += t * moments.at(x, y + j, 0);
        s1 += t * moments.at(x, y + j, 1);
        s2 += t * moments.at(x, y + j, 2);
      }
      const float mean = s1 / s0;
      const float variance = std::max(0.f, s2 / s0 - mean * mean);
      dst.at(x, y) = (src.at(x, y) - mean) / std::sqrt(variance + p.epsilon * p.epsilon);
    }
  });
}

}  // namespace cs::cpu

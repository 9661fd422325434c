// The estimate one pyramid level finer: bilinear, except across the coarse estimate's
// depth edges, where each fine pixel takes the coarse neighbour whose displacement its
// images confirm (backend.hpp upsampleEstimate).
#include <cmath>

#include "cpu_backend.hpp"

namespace cs::cpu {

namespace {

// Sum of |n0(q) - n1(q + shift)| over the window around (x, y), q clamped to the image.
float windowMismatch(const View& n0, const View& n1, int x, int y, float shiftX, float shiftY, int radius) {
  float sum = 0.f;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const int qx = std::min(std::max(x + dx, 0), n0.width - 1), qy = std::min(std::max(y + dy, 0), n0.height - 1);
      sum += std::abs(n0.at(qx, qy) - sampleBilinear(n1, float(qx) + shiftX, float(qy) + shiftY));
    }
  return sum;
}

}  // namespace

void upsampleEstimate(const View& u, const View& w, const View& coarseU, const View& coarseW, const View& n0,
                      const View& n1, const View& mask, const EstimateUpsampleParams& p) {
  const float s = p.scale;
  parallelRows(u.height, [&](int y) {
    const float cy = (float(y) + 0.5f) / s - 0.5f;
    const int iy = std::min(std::max(int(std::floor(cy)), 0), coarseU.height - 2);
    for (int x = 0; x < u.width; ++x) {
      const float cx = (float(x) + 0.5f) / s - 0.5f;
      u.at(x, y) = s * sampleBilinear(coarseU, cx, cy);
      w.at(x, y, 0) = s * sampleBilinear(coarseW, cx, cy, 0);
      w.at(x, y, 1) = s * sampleBilinear(coarseW, cx, cy, 1);
      if (!masked(mask, x, y)) continue;

      // The four coarse neighbours in the contract's order.
      const int ix = std::min(std::max(int(std::floor(cx)), 0), coarseU.width - 2);
      float lowest = s * coarseU.at(ix, iy), highest = lowest;
      for (int k = 1; k < 4; ++k) {
        const float v = s * coarseU.at(ix + k % 2, iy + k / 2);
        lowest = std::min(lowest, v), highest = std::max(highest, v);
      }
      if (highest - lowest < p.edge) continue;

      int best = 0;
      float bestMismatch = 0.f;
      for (int k = 0; k < 4; ++k) {
        const int kx = ix + k % 2, ky = iy + k / 2;
        const float m = windowMismatch(n0, n1, x, y, s * coarseW.at(kx, ky, 0), s * coarseW.at(kx, ky, 1), p.radius);
        if (k == 0 || m < bestMismatch) best = k, bestMismatch = m;
      }
      const int bx = ix + best % 2, by = iy + best / 2;
      u.at(x, y) = s * coarseU.at(bx, by);
      w.at(x, y, 0) = s * coarseW.at(bx, by, 0);
      w.at(x, y, 1) = s * coarseW.at(bx, by, 1);
    }
  });
}

}  // namespace cs::cpu

// The result as the user sees it (backend.hpp finishResult): unsolved pixels NaN in every
// output, the valid mask and z. The host API and the device API both read these buffers.
#include <cmath>
#include <limits>

#include "cpu_backend.hpp"

namespace cs::cpu {

namespace {

bool solvedAt(size_t i, const View& radial, const View& disparity, const View& warp) {
  return !std::isnan(radial.data[i]) && std::isfinite(disparity.data[i]) && std::isfinite(warp.data[2 * i]) &&
         std::isfinite(warp.data[2 * i + 1]);
}

}  // namespace

void finishResult(const View& valid, const View& z, const View& radial, const View& points, const View& disparity,
                  const View& warp, const View& confidence) {
  // The quiet NaN 0x7fc00000, whose bits the CUDA and GLSL kernels write too.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const size_t n = size_t(radial.width) * size_t(radial.height);
  for (size_t i = 0; i < n; ++i) {
    if (solvedAt(i, radial, disparity, warp)) {
      valid.data[i] = 1.f;
      z.data[i] = std::isinf(radial.data[i]) ? radial.data[i] : points.data[3 * i + 2];
      continue;
    }
    valid.data[i] = 0.f;
    z.data[i] = radial.data[i] = disparity.data[i] = confidence.data[i] = nan;
    warp.data[2 * i] = warp.data[2 * i + 1] = nan;
    points.data[3 * i] = points.data[3 * i + 1] = points.data[3 * i + 2] = nan;
  }
}

}  // namespace cs::cpu

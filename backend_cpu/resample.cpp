// Pyramid resampling. Level coordinates follow the pixel-centre convention: fine x maps
// to coarse (x + 0.5) / scale - 0.5.
#include <cmath>

#include "cpu_backend.hpp"

namespace cs::cpu {

namespace {

// Anti-aliasing width of the decimation filter: half the decimation factor.
float decimationSigma(float scale) { return 0.5f * scale; }

}  // namespace

void downsample(const View& dst, const View& src, float scale) {
  const float sigma = decimationSigma(scale);
  const int radius = int(std::ceil(2.f * sigma));
  parallelRows(dst.height, [&](int y) {
    const float cy = (float(y) + 0.5f) * scale - 0.5f;
    for (int x = 0; x < dst.width; ++x) {
      const float cx = (float(x) + 0.5f) * scale - 0.5f;
      for (int c = 0; c < dst.channels; ++c) {
        float sum = 0.f, weights = 0.f;
        for (int j = int(std::floor(cy)) - radius + 1; j <= int(std::floor(cy)) + radius; ++j)
          for (int i = int(std::floor(cx)) - radius + 1; i <= int(std::floor(cx)) + radius; ++i) {
            float dx = float(i) - cx, dy = float(j) - cy;
            float wgt = std::exp(-(dx * dx + dy * dy) / (2.f * sigma * sigma));
            int sx = std::min(std::max(i, 0), src.width - 1), sy = std::min(std::max(j, 0), src.height - 1);
            sum += wgt * src.at(sx, sy, c);
            weights += wgt;
          }
        dst.at(x, y, c) = sum / weights;
      }
    }
  });
}

void upsample(const View& dst, const View& src, float scale, float valueScale) {
  parallelRows(dst.height, [&](int y) {
    const float sy = (float(y) + 0.5f) / scale - 0.5f;
    for (int x = 0; x < dst.width; ++x) {
      const float sx = (float(x) + 0.5f) / scale - 0.5f;
      for (int c = 0; c < dst.channels; ++c) dst.at(x, y, c) = valueScale * sampleBilinear(src, sx, sy, c);
    }
  });
}

}  // namespace cs::cpu

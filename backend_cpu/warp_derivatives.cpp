// Per warp: the tangent of the epipolar curve at the current point x + w, and the
// linearised data term there (I1 sampled at x + w, its derivative along the tangent).
#include <cmath>

#include "cpu_backend.hpp"

namespace cs::cpu {

namespace {

// Five-point central difference of the image along direction g at (x, y).
float derivativeAlong(const View& image, float x, float y, float gx, float gy) {
  auto f = [&](float s) { return sampleBilinear(image, x + s * gx, y + s * gy); };
  return (-f(2.f) + 8.f * f(1.f) - 8.f * f(-1.f) + f(-2.f)) / 12.f;
}

// The stencil must stay on the image and the point on the solved region.
bool sampleable(const View& mask, float x, float y, float gx, float gy) {
  const float reach = 2.f;
  for (float s : {-reach, reach}) {
    float sx = x + s * gx, sy = y + s * gy;
    if (sx < 0.f || sy < 0.f || sx > float(mask.width - 1) || sy > float(mask.height - 1)) return false;
  }
  return masked(mask, int(std::lround(x)), int(std::lround(y)));
}

}  // namespace

void warpDerivatives(const View& u0, const View& iu, const View& iz, const View& tangent, const View& i0,
                     const View& i1, const View& trajectory, const View& w, const View& u, const View& mask,
                     const View* confidence, float weightFloor) {
  parallelRows(mask.height, [&](int y) {
    for (int x = 0; x < mask.width; ++x) {
      u0.at(x, y) = u.at(x, y);
      iu.at(x, y) = iz.at(x, y) = 0.f;
      tangent.at(x, y, 0) = tangent.at(x, y, 1) = 0.f;
      if (!masked(mask, x, y)) continue;

      const float px = float(x) + w.at(x, y, 0), py = float(y) + w.at(x, y, 1);
      float gx = sampleBilinear(trajectory, px, py, 0), gy = sampleBilinear(trajectory, px, py, 1);
      float n = std::sqrt(gx * gx + gy * gy);
      if (n < 1e-3f) {  // interpolated across a flip of the field: keep the pixel's own tangent
        gx = trajectory.at(x, y, 0);
        gy = trajectory.at(x, y, 1);
        n = std::sqrt(gx * gx + gy * gy);
      }
      gx /= n;
      gy /= n;
      tangent.at(x, y, 0) = gx;
      tangent.at(x, y, 1) = gy;
      if (!sampleable(mask, px, py, gx, gy)) continue;  // no data: the regulariser fills in

      const float weight = confidence ? std::max(confidence->at(x, y), weightFloor) : 1.f;
      iz.at(x, y) = weight * (sampleBilinear(i1, px, py) - i0.at(x, y));
      // Averaging both images' derivatives along the curve makes the linearisation
      // symmetric and less sensitive to where the warp currently is.
      iu.at(x, y) =
          weight * 0.5f * (derivativeAlong(i1, px, py, gx, gy) + derivativeAlong(i0, float(x), float(y), gx, gy));
    }
  });
}

}  // namespace cs::cpu

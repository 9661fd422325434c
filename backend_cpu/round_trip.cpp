// The left-right round trip of the final result (backend.hpp roundTrip): a pixel followed
// into image 1 by this solve and back into image 0 by the other direction's. Where both
// solves found the same surface it comes back to itself.
#include <cmath>
#include <limits>

#include "cpu_backend.hpp"

namespace cs::cpu {

namespace {

bool insideImage(const View& v, float x, float y) {
  return x >= 0.f && y >= 0.f && x <= float(v.width - 1) && y <= float(v.height - 1);
}

float roundTripAt(int x, int y, const View& w, const View& calibration, const View& reverseW,
                  const View& reverseCalibration, const View& reverseMask) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float ax = float(x) + w.at(x, y, 0), ay = float(y) + w.at(x, y, 1);
  if (!insideImage(calibration, ax, ay)) return nan;
  const float yx = ax + sampleBilinear(calibration, ax, ay, 0), yy = ay + sampleBilinear(calibration, ax, ay, 1);
  if (!insideImage(reverseW, yx, yy)) return nan;
  if (reverseMask.at(int(std::floor(yx + 0.5f)), int(std::floor(yy + 0.5f))) == 0.f) return nan;
  const float bx = yx + sampleBilinear(reverseW, yx, yy, 0), by = yy + sampleBilinear(reverseW, yx, yy, 1);
  if (!insideImage(reverseCalibration, bx, by)) return nan;
  const float zx = bx + sampleBilinear(reverseCalibration, bx, by, 0);
  const float zy = by + sampleBilinear(reverseCalibration, bx, by, 1);
  const float e = std::sqrt((zx - float(x)) * (zx - float(x)) + (zy - float(y)) * (zy - float(y)));
  return std::isfinite(e) ? e : nan;
}

}  // namespace

void roundTrip(const View& error, const View& w, const View& calibration, const View& reverseW,
               const View& reverseCalibration, const View& reverseMask, const View& mask) {
  parallelRows(error.height, [&](int y) {
    for (int x = 0; x < error.width; ++x)
      error.at(x, y) = masked(mask, x, y) ? roundTripAt(x, y, w, calibration, reverseW, reverseCalibration, reverseMask)
                                          : std::numeric_limits<float>::quiet_NaN();
  });
}

}  // namespace cs::cpu

// The final result's confidence (backend.hpp resultConfidence): how much evidence there is
// for a pixel's estimate, as a product of independent terms, each 1 where nothing speaks
// against it. Also where the evidence is too weak for a depth at all, and where the
// disparity is too small to be told from infinity.
#include <algorithm>
#include <cmath>
#include <limits>

#include "cpu_backend.hpp"

namespace cs::cpu {

namespace {

// How well the image constrains a shift along the epipolar curve: the Cramer-Rao bound of
// a 1-D shift between two images with independent noise is noise^2 * 2 / sum (dI/dg)^2.
float structureTerm(int x, int y, const View& image, const View& trajectory, const View& mask,
                    const ConfidenceParams& p) {
  const float gx = trajectory.at(x, y, 0), gy = trajectory.at(x, y, 1);
  float s = 0.f;
  for (int dy = -p.radius; dy <= p.radius; ++dy)
    for (int dx = -p.radius; dx <= p.radius; ++dx) {
      const int cx = x + dx, cy = y + dy;
      if (!masked(mask, cx, cy) || !masked(mask, cx - 1, cy) || !masked(mask, cx + 1, cy) ||
          !masked(mask, cx, cy - 1) || !masked(mask, cx, cy + 1))
        continue;
      const float ix = 0.5f * (image.at(cx + 1, cy) - image.at(cx - 1, cy));
      const float iy = 0.5f * (image.at(cx, cy + 1) - image.at(cx, cy - 1));
      const float along = gx * ix + gy * iy;
      s += along * along;
    }
  const float signal = s * p.sigmaPx * p.sigmaPx;
  return signal / (signal + 2.f * p.noise * p.noise);
}

// How well the two images agree where the estimate says they should.
float photometricTerm(int x, int y, const View& n0, const View& n1, const View& w, const View& mask,
                      const ConfidenceParams& p) {
  float sum = 0.f;
  int count = 0;
  for (int dy = -p.radius; dy <= p.radius; ++dy)
    for (int dx = -p.radius; dx <= p.radius; ++dx) {
      const int cx = x + dx, cy = y + dy;
      if (!masked(mask, cx, cy)) continue;
      const float wx = w.at(cx, cy, 0), wy = w.at(cx, cy, 1);
      if (!std::isfinite(wx) || !std::isfinite(wy)) continue;
      sum += std::fabs(sampleBilinear(n1, float(cx) + wx, float(cy) + wy) - n0.at(cx, cy));
      ++count;
    }
  if (count == 0) return 0.f;
  const float r = sum / float(count) / p.residualScale;
  return std::exp(-r * r);
}

// Whether the image cannot tell |w| from 0 (|w| < 2 deviations) and bounds it below `bound`
// (|w| + 2 deviations <= bound), the deviation from the structure term s being
// sigmaPx sqrt(1/s - 1). Squared and multiplied by s (sqrt(a) + sqrt(b) <= R squared twice),
// so that every backend decides it alike without a square root or a division.
bool farBelowBound(float w2, float structure, float sigmaPx, float bound) {
  const float b = 4.f * sigmaPx * sigmaPx * (1.f - structure);  // (2 deviations)^2 s
  const float rest = bound * bound * structure - w2 * structure - b;
  return w2 * structure < b && rest >= 0.f && 4.f * w2 * b * structure <= rest * rest;
}

}  // namespace

void resultConfidence(const View& confidence, const View& radial, const View& points, const View& image, const View& n0,
                      const View& n1, const View& w, const View& trajectory, const View* sweepConfidence,
                      const View* roundTripError, const View* planeConfidence, const View& mask,
                      const ConfidenceParams& p) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  parallelRows(confidence.height, [&](int y) {
    for (int x = 0; x < confidence.width; ++x) {
      confidence.at(x, y) = 0.f;
      if (!masked(mask, x, y) || std::isnan(radial.at(x, y))) continue;
      float structure = structureTerm(x, y, image, trajectory, mask, p);
      if (planeConfidence) structure = std::max(structure, planeConfidence->at(x, y));
      float c = structure * photometricTerm(x, y, n0, n1, w, mask, p);
      if (sweepConfidence) {
        float sw = std::min(1.f, std::max(0.f, sweepConfidence->at(x, y)));
        if (planeConfidence) sw = std::max(sw, planeConfidence->at(x, y));
        c *= sw;
      }
      bool invalid = false;
      if (roundTripError) {
        const float e = roundTripError->at(x, y);
        invalid = std::isnan(e) || (p.roundTripMaxPx > 0.f && e > p.roundTripMaxPx);
        const float r = e / p.roundTripPx;
        c *= invalid ? 0.f : std::exp(-r * r);
      }
      const float ratio = p.maxDeviationPx / p.sigmaPx;
      const bool unobservable = p.maxDeviationPx > 0.f && structure < 1.f / (1.f + ratio * ratio);
      if (invalid || unobservable || c < p.invalidBelow) {
        radial.at(x, y) = nan;
        for (int k = 0; k < 3; ++k) points.at(x, y, k) = nan;
        continue;
      }
      confidence.at(x, y) = c;
      const float wx = w.at(x, y, 0), wy = w.at(x, y, 1);
      const float w2 = wx * wx + wy * wy;
      if (w2 < p.infinityPx * p.infinityPx ||
          (p.infinityBoundPx > 0.f && farBelowBound(w2, structure, p.sigmaPx, p.infinityBoundPx))) {
        radial.at(x, y) = std::numeric_limits<float>::infinity();
        for (int k = 0; k < 3; ++k) points.at(x, y, k) = nan;
      }
    }
  });
}

}  // namespace cs::cpu

// The linearised data term of one pixel (cpu/warp_derivatives.cpp), shared by the
// derivatives kernel and the fused median + accumulate + derivatives kernel (median.cu).
#pragma once
#include "common.cuh"

namespace cs::cudak {

__device__ __forceinline__ float derivativeAlong(const Img& image, float x, float y, float gx, float gy) {
  const float f2 = sampleBilinear(image, x + 2.f * gx, y + 2.f * gy);
  const float f1 = sampleBilinear(image, x + 1.f * gx, y + 1.f * gy);
  const float fm1 = sampleBilinear(image, x + -1.f * gx, y + -1.f * gy);
  const float fm2 = sampleBilinear(image, x + -2.f * gx, y + -2.f * gy);
  return (-f2 + 8.f * f1 - 8.f * fm1 + fm2) / 12.f;
}

__device__ __forceinline__ bool sampleable(const Img& mask, float x, float y, float gx, float gy) {
  const float reach = 2.f;
  for (float s : {-reach, reach}) {
    const float sx = x + s * gx, sy = y + s * gy;
    if (sx < 0.f || sy < 0.f || sx > float(mask.width - 1) || sy > float(mask.height - 1)) return false;
  }
  return masked(mask, int(lroundf(x)), int(lroundf(y)));
}

// Pixel (x, y)'s data term for the displacement w = (wx, wy); `isMasked`: its mask value.
__device__ __forceinline__ void dataTermAt(const DataTermOut& out, const DataTermIn& in, int x, int y, bool isMasked,
                                           float wx, float wy) {
  float iuv = 0.f, izv = 0.f, tx = 0.f, ty = 0.f;
  if (isMasked) {
    const float px = float(x) + wx, py = float(y) + wy;
    // Loaded beside the sample, not after it: the fallback below needs it only rarely.
    const float ownGx = at(in.trajectory, x, y, 0), ownGy = at(in.trajectory, x, y, 1);
    float gx = sampleBilinear(in.trajectory, px, py, 0), gy = sampleBilinear(in.trajectory, px, py, 1);
    float n = sqrtf(gx * gx + gy * gy);
    if (n < 1e-3f) {  // interpolated across a flip of the field: keep the pixel's own tangent
      gx = ownGx;
      gy = ownGy;
      n = sqrtf(gx * gx + gy * gy);
    }
    gx /= n;
    gy /= n;
    tx = gx;
    ty = gy;
    // The samples are taken beside the mask test rather than after it (one round trip to
    // memory instead of two; sampleBilinear clamps to the image) and used where it passes.
    const bool reachable = sampleable(in.mask, px, py, gx, gy);
    const float weight = in.confidence.data ? fmaxf(at(in.confidence, x, y), in.weightFloor) : 1.f;
    const float i1Here = sampleBilinear(in.i1, px, py), i0Here = at(in.i0, x, y);
    const float d1 = derivativeAlong(in.i1, px, py, gx, gy);
    const float d0 = derivativeAlong(in.i0, float(x), float(y), gx, gy);
    if (reachable) {
      izv = weight * (i1Here - i0Here);
      iuv = weight * 0.5f * (d1 + d0);
    }
  }
  at(out.iu, x, y) = iuv;
  at(out.iz, x, y) = izv;
  at(out.tangent, x, y, 0) = tx;
  at(out.tangent, x, y, 1) = ty;
}

}  // namespace cs::cudak

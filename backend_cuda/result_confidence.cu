// The final result's confidence (cpu/result_confidence.cpp, backend.hpp resultConfidence):
// structure along the epipolar curve x photometric agreement x the sweep's consistency x the
// round trip; then the invalid pixels and the points at infinity. One thread a pixel, the
// oracle's float arithmetic in its order (no fused multiply-adds).
#include "common.cuh"

namespace cs::cudak {

namespace {

__device__ float structureTerm(int x, int y, const Img& image, const Img& trajectory, const Img& mask,
                               const ConfidenceParams& p) {
  const float gx = at(trajectory, x, y, 0), gy = at(trajectory, x, y, 1);
  float s = 0.f;
  for (int dy = -p.radius; dy <= p.radius; ++dy)
    for (int dx = -p.radius; dx <= p.radius; ++dx) {
      const int cx = x + dx, cy = y + dy;
      if (!masked(mask, cx, cy) || !masked(mask, cx - 1, cy) || !masked(mask, cx + 1, cy) ||
          !masked(mask, cx, cy - 1) || !masked(mask, cx, cy + 1))
        continue;
      const float ix = __fmul_rn(0.5f, at(image, cx + 1, cy) - at(image, cx - 1, cy));
      const float iy = __fmul_rn(0.5f, at(image, cx, cy + 1) - at(image, cx, cy - 1));
      const float along = __fadd_rn(__fmul_rn(gx, ix), __fmul_rn(gy, iy));
      s = __fadd_rn(s, __fmul_rn(along, along));
    }
  const float signal = __fmul_rn(__fmul_rn(s, p.sigmaPx), p.sigmaPx);
  return signal / __fadd_rn(signal, __fmul_rn(__fmul_rn(2.f, p.noise), p.noise));
}

__device__ float photometricTerm(int x, int y, const Img& n0, const Img& n1, const Img& w, const Img& mask,
                                 const ConfidenceParams& p) {
  float sum = 0.f;
  int count = 0;
  for (int dy = -p.radius; dy <= p.radius; ++dy)
    for (int dx = -p.radius; dx <= p.radius; ++dx) {
      const int cx = x + dx, cy = y + dy;
      if (!masked(mask, cx, cy)) continue;
      const float wx = at(w, cx, cy, 0), wy = at(w, cx, cy, 1);
      if (!isfinite(wx) || !isfinite(wy)) continue;
      sum += fabsf(sampleBilinear(n1, __fadd_rn(float(cx), wx), __fadd_rn(float(cy), wy)) - at(n0, cx, cy));
      ++count;
    }
  if (count == 0) return 0.f;
  const float r = sum / float(count) / p.residualScale;
  return expf(-__fmul_rn(r, r));
}

__global__ void resultConfidenceKernel(Img confidence, Img radial, Img points, Img image, Img n0, Img n1, Img w,
                                       Img trajectory, Img sweepConfidence, Img roundTripError, Img mask,
                                       ConfidenceParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= confidence.width || y >= confidence.height) return;
  const float nan = __int_as_float(0x7fc00000);
  at(confidence, x, y) = 0.f;
  if (!masked(mask, x, y) || isnan(at(radial, x, y))) return;
  const float structure = structureTerm(x, y, image, trajectory, mask, p);
  float c = __fmul_rn(structure, photometricTerm(x, y, n0, n1, w, mask, p));
  if (sweepConfidence.data) c = __fmul_rn(c, fminf(1.f, fmaxf(0.f, at(sweepConfidence, x, y))));
  bool invalid = false;
  if (roundTripError.data) {
    const float e = at(roundTripError, x, y);
    invalid = isnan(e) || (p.roundTripMaxPx > 0.f && e > p.roundTripMaxPx);
    const float r = e / p.roundTripPx;
    c = __fmul_rn(c, invalid ? 0.f : expf(-__fmul_rn(r, r)));
  }
  const float ratio = p.maxDeviationPx / p.sigmaPx;
  const bool unobservable = p.maxDeviationPx > 0.f && structure < 1.f / __fadd_rn(1.f, __fmul_rn(ratio, ratio));
  if (invalid || unobservable || c < p.invalidBelow) {
    at(radial, x, y) = nan;
    for (int k = 0; k < 3; ++k) at(points, x, y, k) = nan;
    return;
  }
  at(confidence, x, y) = c;
  const float wx = at(w, x, y, 0), wy = at(w, x, y, 1);
  if (__fadd_rn(__fmul_rn(wx, wx), __fmul_rn(wy, wy)) < __fmul_rn(p.infinityPx, p.infinityPx)) {
    at(radial, x, y) = __int_as_float(0x7f800000);
    for (int k = 0; k < 3; ++k) at(points, x, y, k) = nan;
  }
}

}  // namespace

cudaError_t launchResultConfidence(cudaStream_t s, Img confidence, Img radial, Img points, Img image, Img n0, Img n1,
                                   Img w, Img trajectory, Img sweepConfidence, Img roundTripError, Img mask,
                                   const ConfidenceParams& p) {
  const dim3 block(32, 8);
  CS_LAUNCH(resultConfidenceKernel, grid2d(confidence.width, confidence.height, block), block, 0, s, confidence, radial,
            points, image, n0, n1, w, trajectory, sweepConfidence, roundTripError, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak

// The final result's confidence (cpu/result_confidence.cpp, backend.hpp resultConfidence):
// structure along the epipolar curve x photometric agreement x the sweep's consistency x the
// round trip; then the invalid pixels and the points at infinity. Two passes of one thread
// a pixel (each pixel's share of the windows, then the windows' sums), the oracle's float
// arithmetic in its order (no fused multiply-adds).
#include "common.cuh"

namespace cs::cudak {

namespace {

// Pass 1: what a pixel adds to every window that holds it, computed once instead of once
// per window (49 times with the 7x7 window): its gradient (x, y) where it and its four
// neighbours are masked (flag 1), and its photometric residual (z) where it is masked with a
// finite warp (flag 2). Pass 2 adds the same values in the oracle's order, so the result is
// unchanged bit for bit; the window's loads fall from about 14 floats a pixel to one float4.
__global__ void confidenceTermsKernel(float4* terms, Img image, Img n0, Img n1, Img w, Img mask) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= mask.width || y >= mask.height) return;
  float4 t = make_float4(0.f, 0.f, 0.f, 0.f);
  int flags = 0;
  if (masked(mask, x, y) && masked(mask, x - 1, y) && masked(mask, x + 1, y) && masked(mask, x, y - 1) &&
      masked(mask, x, y + 1)) {
    t.x = __fmul_rn(0.5f, at(image, x + 1, y) - at(image, x - 1, y));
    t.y = __fmul_rn(0.5f, at(image, x, y + 1) - at(image, x, y - 1));
    flags |= 1;
  }
  const float wx = at(w, x, y, 0), wy = at(w, x, y, 1);
  if (masked(mask, x, y) && isfinite(wx) && isfinite(wy)) {
    t.z = fabsf(sampleBilinear(n1, __fadd_rn(float(x), wx), __fadd_rn(float(y), wy)) - at(n0, x, y));
    flags |= 2;
  }
  t.w = float(flags);
  terms[size_t(y) * mask.width + x] = t;
}

struct WindowTerms {
  float structure, photometric;
};

// Pass 2's sums over the window around (x, y), in the oracle's order (rows, then columns).
__device__ WindowTerms windowTerms(int x, int y, const float4* terms, const Img& trajectory, const Img& mask,
                                   const ConfidenceParams& p) {
  const float gx = at(trajectory, x, y, 0), gy = at(trajectory, x, y, 1);
  float s = 0.f, sum = 0.f;
  int count = 0;
  for (int dy = -p.radius; dy <= p.radius; ++dy)
    for (int dx = -p.radius; dx <= p.radius; ++dx) {
      const int cx = x + dx, cy = y + dy;
      if (!inside(mask, cx, cy)) continue;
      const float4 t = terms[size_t(cy) * mask.width + cx];
      const int flags = int(t.w);
      if (flags & 1) {
        const float along = __fadd_rn(__fmul_rn(gx, t.x), __fmul_rn(gy, t.y));
        s = __fadd_rn(s, __fmul_rn(along, along));
      }
      if (flags & 2) {
        sum = __fadd_rn(sum, t.z);
        ++count;
      }
    }
  const float signal = __fmul_rn(__fmul_rn(s, p.sigmaPx), p.sigmaPx);
  WindowTerms out;
  out.structure = signal / __fadd_rn(signal, __fmul_rn(__fmul_rn(2.f, p.noise), p.noise));
  const float r = sum / float(max(count, 1)) / p.residualScale;
  out.photometric = count == 0 ? 0.f : expf(-__fmul_rn(r, r));
  return out;
}

// backend_cpu/result_confidence.cpp farBelowBound: |w| < 2 deviations, |w| + 2 deviations <= bound.
__device__ bool farBelowBound(float w2, float structure, float sigmaPx, float bound) {
  const float b = __fmul_rn(__fmul_rn(__fmul_rn(4.f, sigmaPx), sigmaPx), __fsub_rn(1.f, structure));
  const float rest = __fsub_rn(__fsub_rn(__fmul_rn(__fmul_rn(bound, bound), structure), __fmul_rn(w2, structure)), b);
  return __fmul_rn(w2, structure) < b && rest >= 0.f &&
         __fmul_rn(__fmul_rn(__fmul_rn(4.f, w2), b), structure) <= __fmul_rn(rest, rest);
}

__global__ void resultConfidenceKernel(Img confidence, Img radial, Img points, const float4* terms, Img w,
                                       Img trajectory, Img sweepConfidence, Img roundTripError, Img planeConfidence,
                                       Img mask, ConfidenceParams p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= confidence.width || y >= confidence.height) return;
  const float nan = __int_as_float(0x7fc00000);
  at(confidence, x, y) = 0.f;
  if (!masked(mask, x, y) || isnan(at(radial, x, y))) return;
  const WindowTerms terms2 = windowTerms(x, y, terms, trajectory, mask, p);
  const float structure = planeConfidence.data ? fmaxf(terms2.structure, at(planeConfidence, x, y)) : terms2.structure;
  float c = __fmul_rn(structure, terms2.photometric);
  if (sweepConfidence.data) {
    float sweep = fminf(1.f, fmaxf(0.f, at(sweepConfidence, x, y)));
    if (planeConfidence.data) sweep = fmaxf(sweep, at(planeConfidence, x, y));
    c = __fmul_rn(c, sweep);
  }
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
  const float w2 = __fadd_rn(__fmul_rn(wx, wx), __fmul_rn(wy, wy));
  if (w2 < __fmul_rn(p.infinityPx, p.infinityPx) ||
      (p.infinityBoundPx > 0.f && farBelowBound(w2, structure, p.sigmaPx, p.infinityBoundPx))) {
    at(radial, x, y) = __int_as_float(0x7f800000);
    for (int k = 0; k < 3; ++k) at(points, x, y, k) = nan;
  }
}

}  // namespace

cudaError_t launchResultConfidence(cudaStream_t s, Img confidence, Img radial, Img points, Img image, Img n0, Img n1,
                                   Img w, Img trajectory, Img sweepConfidence, Img roundTripError, Img planeConfidence,
                                   Img mask, const ConfidenceParams& p, float* scratch) {
  const dim3 block(32, 8);
  const dim3 grid = grid2d(confidence.width, confidence.height, block);
  float4* terms = reinterpret_cast<float4*>(scratch);
  CS_LAUNCH(confidenceTermsKernel, grid, block, 0, s, terms, image, n0, n1, w, mask);
  CS_LAUNCH(resultConfidenceKernel, grid, block, 0, s, confidence, radial, points, terms, w, trajectory,
            sweepConfidence, roundTripError, planeConfidence, mask, p);
  return cudaGetLastError();
}

}  // namespace cs::cudak

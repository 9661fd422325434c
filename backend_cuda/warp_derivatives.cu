// Per warp: the tangent of the epipolar curve at x + w and the linearised data term
// there (cpu/warp_derivatives.cpp).
#include "common.cuh"

namespace cs::cudak {

namespace {

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

__global__ void warpDerivativesKernel(Img u0, Img iu, Img iz, Img tangent, Img i0, Img i1, Img trajectory, Img w, Img u,
                                      Img mask, Img confidence, float weightFloor) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= mask.width || y >= mask.height) return;
  at(u0, x, y) = at(u, x, y);
  float iuv = 0.f, izv = 0.f, tx = 0.f, ty = 0.f;
  if (at(mask, x, y) != 0.f) {
    const float px = float(x) + at(w, x, y, 0), py = float(y) + at(w, x, y, 1);
    float gx = sampleBilinear(trajectory, px, py, 0), gy = sampleBilinear(trajectory, px, py, 1);
    float n = sqrtf(gx * gx + gy * gy);
    if (n < 1e-3f) {  // interpolated across a flip of the field: keep the pixel's own tangent
      gx = at(trajectory, x, y, 0);
      gy = at(trajectory, x, y, 1);
      n = sqrtf(gx * gx + gy * gy);
    }
    gx /= n;
    gy /= n;
    tx = gx;
    ty = gy;
    if (sampleable(mask, px, py, gx, gy)) {
      const float weight = confidence.data ? fmaxf(at(confidence, x, y), weightFloor) : 1.f;
      izv = weight * (sampleBilinear(i1, px, py) - at(i0, x, y));
      iuv = weight * 0.5f * (derivativeAlong(i1, px, py, gx, gy) + derivativeAlong(i0, float(x), float(y), gx, gy));
    }
  }
  at(iu, x, y) = iuv;
  at(iz, x, y) = izv;
  at(tangent, x, y, 0) = tx;
  at(tangent, x, y, 1) = ty;
}

}  // namespace

cudaError_t launchWarpDerivatives(cudaStream_t s, Img u0, Img iu, Img iz, Img tangent, Img i0, Img i1, Img trajectory,
                                  Img w, Img u, Img mask, Img confidence, float weightFloor) {
  const dim3 block(32, 8);
  CS_LAUNCH(warpDerivativesKernel, grid2d(mask.width, mask.height, block), block, 0, s, u0, iu, iz, tangent, i0, i1,
            trajectory, w, u, mask, confidence, weightFloor);
  return cudaGetLastError();
}

}  // namespace cs::cudak

// The estimate one pyramid level finer: bilinear, except across the coarse estimate's
// depth edges, where each fine pixel takes the coarse neighbour whose displacement its
// images confirm (cpu/upsample_estimate.cpp, backend.hpp upsampleEstimate). Edge pixels
// are a few percent of the image, so the plain per-pixel form is enough.
#include "common.cuh"

namespace cs::cudak {

namespace {

__device__ float windowMismatch(const Img& n0, const Img& n1, int x, int y, float shiftX, float shiftY, int radius) {
  float sum = 0.f;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const int qx = min(max(x + dx, 0), n0.width - 1), qy = min(max(y + dy, 0), n0.height - 1);
      sum += fabsf(at(n0, qx, qy) - sampleBilinear(n1, float(qx) + shiftX, float(qy) + shiftY));
    }
  return sum;
}

__global__ void upsampleEstimateKernel(Img u, Img w, Img coarseU, Img coarseW, Img n0, Img n1, Img mask,
                                       EstimateUpsampleDev p) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  const float s = p.scale;
  const float cx = (float(x) + 0.5f) / s - 0.5f, cy = (float(y) + 0.5f) / s - 0.5f;
  float uOut = s * sampleBilinear(coarseU, cx, cy);
  float wx = s * sampleBilinear(coarseW, cx, cy, 0), wy = s * sampleBilinear(coarseW, cx, cy, 1);
  if (masked(mask, x, y)) {
    const int ix = min(max(int(floorf(cx)), 0), coarseU.width - 2);
    const int iy = min(max(int(floorf(cy)), 0), coarseU.height - 2);
    float lowest = s * at(coarseU, ix, iy), highest = lowest;
    for (int k = 1; k < 4; ++k) {
      const float v = s * at(coarseU, ix + k % 2, iy + k / 2);
      lowest = fminf(lowest, v), highest = fmaxf(highest, v);
    }
    if (highest - lowest >= p.edge) {
      int best = 0;
      float bestMismatch = 0.f;
      for (int k = 0; k < 4; ++k) {
        const int kx = ix + k % 2, ky = iy + k / 2;
        const float m = windowMismatch(n0, n1, x, y, s * at(coarseW, kx, ky, 0), s * at(coarseW, kx, ky, 1), p.radius);
        if (k == 0 || m < bestMismatch) best = k, bestMismatch = m;
      }
      const int bx = ix + best % 2, by = iy + best / 2;
      uOut = s * at(coarseU, bx, by);
      wx = s * at(coarseW, bx, by, 0);
      wy = s * at(coarseW, bx, by, 1);
    }
  }
  at(u, x, y) = uOut;
  at(w, x, y, 0) = wx;
  at(w, x, y, 1) = wy;
}

}  // namespace

cudaError_t launchUpsampleEstimate(cudaStream_t s, Img u, Img w, Img coarseU, Img coarseW, Img n0, Img n1, Img mask,
                                   const EstimateUpsampleDev& p) {
  const dim3 block(32, 8);
  CS_LAUNCH(upsampleEstimateKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, coarseU, coarseW, n0, n1, mask,
            p);
  return cudaGetLastError();
}

}  // namespace cs::cudak

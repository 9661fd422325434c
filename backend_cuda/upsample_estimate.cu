// The estimate one pyramid level finer: bilinear, except across the coarse estimate's
// depth edges, where each fine pixel takes the coarse neighbour whose displacement its
// images confirm (cpu/upsample_estimate.cpp, backend.hpp upsampleEstimate). One thread a
// pixel; the window is a template parameter so that image 0's stays in registers.
#include "common.cuh"

namespace cs::cudak {

namespace {

// The oracle's window sum (cpu/upsample_estimate.cpp windowMismatch), same order, with
// image 0's window loaded once for the four candidates.
template <int R>
__device__ float windowMismatch(const float (&window0)[(2 * R + 1) * (2 * R + 1)], const Img& n1, int x, int y,
                                float shiftX, float shiftY) {
  float sum = 0.f;
#pragma unroll
  for (int dy = -R; dy <= R; ++dy)
#pragma unroll
    for (int dx = -R; dx <= R; ++dx) {
      const int qx = min(max(x + dx, 0), n1.width - 1), qy = min(max(y + dy, 0), n1.height - 1);
      sum +=
          fabsf(window0[(dy + R) * (2 * R + 1) + dx + R] - sampleBilinear(n1, float(qx) + shiftX, float(qy) + shiftY));
    }
  return sum;
}

// Of the four coarse neighbours (ix, iy) + (k % 2, k / 2), the one whose displacement
// image 1 confirms best; the first on ties. A neighbour equal to an earlier one scores
// the same and cannot win, so it is not scored again.
template <int R>
__device__ int bestNeighbour(const Img& coarseU, const Img& coarseW, const Img& n0, const Img& n1, int x, int y, int ix,
                             int iy, float s) {
  float window0[(2 * R + 1) * (2 * R + 1)];
#pragma unroll
  for (int dy = -R; dy <= R; ++dy)
#pragma unroll
    for (int dx = -R; dx <= R; ++dx)
      window0[(dy + R) * (2 * R + 1) + dx + R] =
          at(n0, min(max(x + dx, 0), n0.width - 1), min(max(y + dy, 0), n0.height - 1));
  int best = 0;
  float bestMismatch = 0.f;
  for (int k = 0; k < 4; ++k) {
    const int kx = ix + k % 2, ky = iy + k / 2;
    const float u = at(coarseU, kx, ky), wx = at(coarseW, kx, ky, 0), wy = at(coarseW, kx, ky, 1);
    bool seen = false;
    for (int j = 0; j < k; ++j) {
      const int jx = ix + j % 2, jy = iy + j / 2;
      seen |= at(coarseU, jx, jy) == u && at(coarseW, jx, jy, 0) == wx && at(coarseW, jx, jy, 1) == wy;
    }
    if (seen) continue;
    const float m = windowMismatch<R>(window0, n1, x, y, s * wx, s * wy);
    if (k == 0 || m < bestMismatch) best = k, bestMismatch = m;
  }
  return best;
}

template <int R>
__global__ void upsampleEstimateKernel(Img u, Img w, Img coarseU, Img coarseW, Img n0, Img n1, Img mask, float s,
                                       float edge) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
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
    if (highest - lowest >= edge) {
      const int best = bestNeighbour<R>(coarseU, coarseW, n0, n1, x, y, ix, iy, s);
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
  const dim3 grid = grid2d(u.width, u.height, block);
  switch (p.radius) {  // 0 to kMaxUpsampleRadius (the contract)
#define CS_UPSAMPLE_ESTIMATE(R)                                                                                     \
  case R:                                                                                                           \
    CS_LAUNCH(upsampleEstimateKernel<R>, grid, block, 0, s, u, w, coarseU, coarseW, n0, n1, mask, p.scale, p.edge); \
    break;
    CS_UPSAMPLE_ESTIMATE(0)
    CS_UPSAMPLE_ESTIMATE(1)
    CS_UPSAMPLE_ESTIMATE(2)
    CS_UPSAMPLE_ESTIMATE(3)
    CS_UPSAMPLE_ESTIMATE(4)
#undef CS_UPSAMPLE_ESTIMATE
    default:
      return cudaErrorInvalidValue;
  }
  return cudaGetLastError();
}

}  // namespace cs::cudak

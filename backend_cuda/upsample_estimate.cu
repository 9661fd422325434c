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

// The four coarse neighbours (ix, iy) + (k % 2, k / 2) of a fine pixel, in the contract's
// order, their disparities and displacements already scaled to the fine level.
struct Neighbours {
  float u[4], wx[4], wy[4];
};

__device__ Neighbours loadNeighbours(const Img& coarseU, const Img& coarseW, int ix, int iy, float s) {
  Neighbours n;
#pragma unroll
  for (int k = 0; k < 4; ++k) {
    const int kx = ix + k % 2, ky = iy + k / 2;
    n.u[k] = s * at(coarseU, kx, ky);
    n.wx[k] = s * at(coarseW, kx, ky, 0);
    n.wy[k] = s * at(coarseW, kx, ky, 1);
  }
  return n;
}

// The neighbour whose displacement image 1 confirms best; the first on ties. A neighbour
// equal to an earlier one scores the same and cannot win, so it is not scored again.
template <int R>
__device__ int bestNeighbour(const Neighbours& n, const Img& n0, const Img& n1, int x, int y) {
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
    bool seen = false;
#pragma unroll
    for (int j = 0; j < k; ++j) seen |= n.u[j] == n.u[k] && n.wx[j] == n.wx[k] && n.wy[j] == n.wy[k];
    if (seen) continue;
    const float m = windowMismatch<R>(window0, n1, x, y, n.wx[k], n.wy[k]);
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
    const Neighbours n = loadNeighbours(coarseU, coarseW, ix, iy, s);
    const float lowest = fminf(fminf(n.u[0], n.u[1]), fminf(n.u[2], n.u[3]));
    const float highest = fmaxf(fmaxf(n.u[0], n.u[1]), fmaxf(n.u[2], n.u[3]));
    if (highest - lowest >= edge) {
      const int best = bestNeighbour<R>(n, n0, n1, x, y);
      uOut = n.u[best];
      wx = n.wx[best];
      wy = n.wy[best];
    }
  }
  at(u, x, y) = uOut;
  at(w, x, y, 0) = wx;
  at(w, x, y, 1) = wy;
}

}  // namespace

cudaError_t launchUpsampleEstimate(cudaStream_t s, Img u, Img w, Img coarseU, Img coarseW, Img n0, Img n1, Img mask,
                                   const EstimateUpsampleParams& p) {
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

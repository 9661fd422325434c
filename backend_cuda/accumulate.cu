// du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent (cpu/accumulate.cpp), and
// optionally the next warp's derivatives of the pixel (warp_derivatives.cuh).
#include "warp_derivatives.cuh"

namespace cs::cudak {

namespace {
template <bool kNextWarp>
__global__ void accumulateKernel(Img u, Img w, Img u0, Img tangent, Img mask, float duMax, DataTermOut nextOut,
                                 DataTermIn next) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height) return;
  const bool isMasked = masked(mask, x, y);
  float uNew = 0.f, wx = 0.f, wy = 0.f;
  if (isMasked) uNew = accumulatePixel(u, w, u0, tangent, x, y, at(u, x, y), duMax, wx, wy);
  if (!kNextWarp) return;
  at(u0, x, y) = isMasked ? uNew : at(u, x, y);
  dataTermAt(nextOut, next, x, y, isMasked, wx, wy);
}
}  // namespace

cudaError_t launchAccumulate(cudaStream_t s, Img u, Img w, Img u0, Img tangent, Img mask, float duMax,
                             const DataTermOut* nextOut, const DataTermIn* next) {
  const dim3 block(32, 8);
  const dim3 grid = grid2d(u.width, u.height, block);
  if (next)
    CS_LAUNCH(accumulateKernel<true>, grid, block, 0, s, u, w, u0, tangent, mask, duMax, *nextOut, *next);
  else
    CS_LAUNCH(accumulateKernel<false>, grid, block, 0, s, u, w, u0, tangent, mask, duMax, DataTermOut{}, DataTermIn{});
  return cudaSuccess;
}

}  // namespace cs::cudak

// du = clamp(u - u0, +-duMax); u = u0 + du; w += du * tangent (cpu/accumulate.cpp).
#include "common.cuh"

namespace cs::cudak {

namespace {
__global__ void accumulateKernel(Img u, Img w, Img u0, Img tangent, Img mask, float duMax) {
  beginKernel();
  const int x = blockIdx.x * blockDim.x + threadIdx.x, y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= u.width || y >= u.height || !masked(mask, x, y)) return;
  accumulatePixel(u, w, u0, tangent, x, y, at(u, x, y), duMax);
}
}  // namespace

cudaError_t launchAccumulate(cudaStream_t s, Img u, Img w, Img u0, Img tangent, Img mask, float duMax) {
  const dim3 block(32, 8);
  CS_LAUNCH(accumulateKernel, grid2d(u.width, u.height, block), block, 0, s, u, w, u0, tangent, mask, duMax);
  return cudaSuccess;
}

}  // namespace cs::cudak
